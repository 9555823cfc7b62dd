/**
 * Edit operations on a model. Each is pure: it takes a model and returns a new
 * one (the input is never changed), or throws an `EditError` that says why the
 * edit is refused. References are kept consistent: renaming a sensor renames
 * the topics that publishers and subscribers name, and moves layout entries.
 *
 * @example
 *   let { model, id } = addSensor(emptyModel(), "gps");
 *   model = addVariable(model, "gps", "lat", "RADIAN").model;
 *   model = rename(model, "sensor:gps", "gnss"); // topics become usv.gnss.lat
 */
import type { Aggregation, ModdModel, Position, Publisher, Subscriber } from "./model.gen";
import {
  DRONE_ID, PUB_BROKER_ID, SUB_BROKER_ID, LINK_ID,
  parseId, publisherId, sensorId, subscriberId, topicId, topicName,
} from "./ids";
import { AGGREGATION } from "./contracts.gen";
import { listTopics } from "./query";
import { freshName } from "./templates";

export class EditError extends Error {
  constructor(message: string) {
    super(message);
    this.name = "EditError";
  }
}

export const NAME_PATTERN = /^[A-Za-z_][A-Za-z0-9_]*$/;

export interface Created {
  model: ModdModel;
  /** Element id of what was created. */
  id: string;
}

const clone = (m: ModdModel): ModdModel => structuredClone(m);

function setPosition(m: ModdModel, id: string, pos: Position | undefined): void {
  if (!pos) return;
  m.layout = { ...(m.layout ?? {}), nodes: { ...(m.layout?.nodes ?? {}), [id]: pos } };
}

/** Names of publishers and subscribers: one namespace (the schema says so). */
function clientNames(m: ModdModel): string[] {
  return [...m.publishers.map((p) => p.name), ...m.subscribers.map((s) => s.name)];
}

function checkName(name: string): void {
  if (!NAME_PATTERN.test(name)) {
    throw new EditError(`"${name}" is not a name: a letter or _, then letters, digits or _`);
  }
}

export function addSensor(model: ModdModel, name?: string, pos?: Position): Created {
  const m = clone(model);
  const n = name ?? freshName("sensor", m.drone.sensors.map((s) => s.name));
  checkName(n);
  if (m.drone.sensors.some((s) => s.name === n)) throw new EditError(`sensor "${n}" exists already`);
  // The schema asks for at least one variable: a new sensor comes with one, named as
  // + Variable names the next ones (var_1, var_2, …), like sensor_1, pub_1, sub_1.
  m.drone.sensors.push({ name: n, variables: [{ name: freshName("var", []), unit: "NONE" }] });
  setPosition(m, sensorId(n), pos);
  return { model: m, id: sensorId(n) };
}

export function addVariable(
  model: ModdModel, sensor: string, name?: string, unit = "NONE", pos?: Position,
): Created {
  const m = clone(model);
  const s = m.drone.sensors.find((x) => x.name === sensor);
  if (!s) throw new EditError(`no sensor "${sensor}"`);
  const n = name ?? freshName("var", s.variables.map((v) => v.name));
  checkName(n);
  if (s.variables.some((v) => v.name === n)) throw new EditError(`"${sensor}" measures "${n}" already`);
  s.variables.push({ name: n, unit });
  setPosition(m, topicId(sensor, n), pos);
  return { model: m, id: topicId(sensor, n) };
}

export function addPublisher(model: ModdModel, name?: string, periodS = "1.0", pos?: Position): Created {
  const m = clone(model);
  const n = name ?? freshName("pub", clientNames(m));
  checkName(n);
  if (clientNames(m).includes(n)) throw new EditError(`"${n}" names a publisher or subscriber already`);
  m.publishers.push({ name: n, periodS, topics: [] });
  setPosition(m, publisherId(n), pos);
  return { model: m, id: publisherId(n) };
}

export function addSubscriber(
  model: ModdModel,
  opts: { name?: string; topic?: string; periodS?: string; aggregation?: Aggregation } = {},
  pos?: Position,
): Created {
  const m = clone(model);
  const n = opts.name ?? freshName("sub", clientNames(m));
  checkName(n);
  if (clientNames(m).includes(n)) throw new EditError(`"${n}" names a publisher or subscriber already`);
  // An unconnected subscriber has an empty topic: validation flags it until it is connected.
  m.subscribers.push({
    name: n, topic: opts.topic ?? "", periodS: opts.periodS ?? "1.0", aggregation: opts.aggregation ?? AGGREGATION.AVERAGE,
  });
  setPosition(m, subscriberId(n), pos);
  return { model: m, id: subscriberId(n) };
}

function dropLayout(m: ModdModel, ids: string[]): void {
  if (!m.layout?.nodes) return;
  const nodes = { ...m.layout.nodes };
  for (const id of ids) delete nodes[id];
  m.layout = { ...m.layout, nodes };
}

/** Removes topic names from publishers and empties subscribers that named them. */
function dropTopicRefs(m: ModdModel, names: Set<string>): void {
  for (const p of m.publishers) p.topics = p.topics.filter((t) => !names.has(t));
  for (const s of m.subscribers) if (names.has(s.topic)) s.topic = "";
}

/**
 * Removes an element and what only it holds (a sensor's variables), and the
 * references to it. The drone, the brokers and the link cannot be removed;
 * nor can a sensor's last variable (a sensor measures at least one).
 */
export function removeElement(model: ModdModel, id: string): ModdModel {
  const p = parseId(id);
  if (!p) throw new EditError(`unknown element "${id}"`);
  const m = clone(model);
  switch (p.kind) {
    case "drone": case "pubBroker": case "subBroker": case "link":
      throw new EditError(`the ${p.kind === "link" ? "link" : p.kind} cannot be removed`);
    case "sensor": {
      const s = m.drone.sensors.find((x) => x.name === p.sensor);
      if (!s) throw new EditError(`no sensor "${p.sensor}"`);
      m.drone.sensors = m.drone.sensors.filter((x) => x !== s);
      dropTopicRefs(m, new Set(s.variables.map((v) => topicName(m.drone.name, s.name, v.name))));
      dropLayout(m, [id, ...s.variables.map((v) => topicId(s.name, v.name))]);
      return m;
    }
    case "topic": {
      const s = m.drone.sensors.find((x) => x.name === p.sensor);
      const v = s?.variables.find((x) => x.name === p.variable);
      if (!s || !v) throw new EditError(`no measured variable "${p.name}"`);
      if (s.variables.length === 1) {
        throw new EditError(`"${s.name}" must measure at least one variable: remove the sensor instead`);
      }
      s.variables = s.variables.filter((x) => x !== v);
      dropTopicRefs(m, new Set([topicName(m.drone.name, s.name, v.name)]));
      dropLayout(m, [id]);
      return m;
    }
    case "publisher": {
      if (!m.publishers.some((x) => x.name === p.name)) throw new EditError(`no publisher "${p.name}"`);
      m.publishers = m.publishers.filter((x) => x.name !== p.name);
      dropLayout(m, [id]);
      return m;
    }
    case "subscriber": {
      if (!m.subscribers.some((x) => x.name === p.name)) throw new EditError(`no subscriber "${p.name}"`);
      m.subscribers = m.subscribers.filter((x) => x.name !== p.name);
      dropLayout(m, [id]);
      return m;
    }
  }
}

/** Removes several elements; ones that cannot be removed are skipped and reported. */
export function removeElements(model: ModdModel, ids: string[]): { model: ModdModel; refused: string[] } {
  let m = model;
  const refused: string[] = [];
  // Topics before sensors, so removing a sensor with its topics selected works.
  const order = [...ids].sort((a, b) => Number(a.startsWith("sensor:")) - Number(b.startsWith("sensor:")));
  for (const id of order) {
    try {
      m = removeElement(m, id);
    } catch (e) {
      if (!(e instanceof EditError)) throw e;
      // A topic already removed with its sensor is not a refusal.
      if (!(parseId(id)?.kind === "topic" && !listTopics(m).some((t) => t.id === id))) refused.push(e.message);
    }
  }
  return { model: m, refused };
}

function topicById(m: ModdModel, id: string): string {
  const t = listTopics(m).find((x) => x.id === id);
  if (!t) throw new EditError(`no measured variable "${id}"`);
  return t.name;
}

/** Whether dragging from `source` to `target` makes an edge (publisher → topic, topic → subscriber). */
export function canConnect(model: ModdModel, source: string, target: string): boolean {
  try {
    connect(model, source, target);
    return true;
  } catch {
    return false;
  }
}

/**
 * Connects publisher → topic (the publisher publishes it) or topic →
 * subscriber (the subscriber's topic becomes it, replacing the previous one).
 */
export function connect(model: ModdModel, source: string, target: string): ModdModel {
  const s = parseId(source);
  const t = parseId(target);
  const m = clone(model);
  if (s?.kind === "publisher" && t?.kind === "topic") {
    const pub = m.publishers.find((x) => x.name === s.name);
    if (!pub) throw new EditError(`no publisher "${s.name}"`);
    const name = topicById(m, target);
    if (pub.topics.includes(name)) throw new EditError(`${pub.name} publishes ${name} already`);
    pub.topics.push(name);
    return m;
  }
  if (s?.kind === "topic" && t?.kind === "subscriber") {
    const sub = m.subscribers.find((x) => x.name === t.name);
    if (!sub) throw new EditError(`no subscriber "${t.name}"`);
    const name = topicById(m, source);
    if (sub.topic === name) throw new EditError(`${sub.name} subscribes to ${name} already`);
    sub.topic = name;
    return m;
  }
  throw new EditError("connect a publisher to a topic, or a topic to a subscriber");
}

/** Removes a publishes/subscribes edge given its two ends. */
export function disconnect(model: ModdModel, source: string, target: string): ModdModel {
  const s = parseId(source);
  const t = parseId(target);
  const m = clone(model);
  if (s?.kind === "publisher" && t?.kind === "topic") {
    const name = topicById(m, target);
    const pub = m.publishers.find((x) => x.name === s.name);
    if (!pub) throw new EditError(`no publisher "${s.name}"`);
    pub.topics = pub.topics.filter((x) => x !== name);
    return m;
  }
  if (s?.kind === "topic" && t?.kind === "subscriber") {
    const sub = m.subscribers.find((x) => x.name === t.name);
    if (!sub) throw new EditError(`no subscriber "${t.name}"`);
    sub.topic = "";
    return m;
  }
  throw new EditError("only publisher → topic and topic → subscriber edges can be removed");
}

function moveLayoutKeys(m: ModdModel, moves: Array<[string, string]>): void {
  const nodes = m.layout?.nodes;
  if (!nodes) return;
  const next = { ...nodes };
  for (const [from, to] of moves) {
    if (from in next) {
      next[to] = next[from];
      delete next[from];
    }
  }
  m.layout = { ...m.layout, nodes: next };
}

function renameTopics(m: ModdModel, map: Map<string, string>): void {
  for (const p of m.publishers) p.topics = p.topics.map((t) => map.get(t) ?? t);
  for (const s of m.subscribers) s.topic = map.get(s.topic) ?? s.topic;
}

/**
 * Renames an element and updates every reference to it: topic names in
 * publishers and subscribers, and layout keys.
 */
export function rename(model: ModdModel, id: string, newName: string): ModdModel {
  checkName(newName);
  const p = parseId(id);
  if (!p) throw new EditError(`unknown element "${id}"`);
  const m = clone(model);
  const drone = m.drone.name;
  switch (p.kind) {
    case "drone": {
      const map = new Map<string, string>();
      for (const t of listTopics(m)) map.set(t.name, topicName(newName, t.sensor.name, t.variable.name));
      m.drone.name = newName;
      renameTopics(m, map);
      return m;
    }
    case "pubBroker": m.pubBroker.name = newName; return m;
    case "subBroker": m.subBroker.name = newName; return m;
    case "link": throw new EditError("the link has no name");
    case "sensor": {
      const s = m.drone.sensors.find((x) => x.name === p.sensor);
      if (!s) throw new EditError(`no sensor "${p.sensor}"`);
      if (newName === s.name) return model;
      if (m.drone.sensors.some((x) => x.name === newName)) throw new EditError(`sensor "${newName}" exists already`);
      const map = new Map<string, string>();
      const moves: Array<[string, string]> = [[id, sensorId(newName)]];
      for (const v of s.variables) {
        map.set(topicName(drone, s.name, v.name), topicName(drone, newName, v.name));
        moves.push([topicId(s.name, v.name), topicId(newName, v.name)]);
      }
      s.name = newName;
      renameTopics(m, map);
      moveLayoutKeys(m, moves);
      return m;
    }
    case "topic": {
      const s = m.drone.sensors.find((x) => x.name === p.sensor);
      const v = s?.variables.find((x) => x.name === p.variable);
      if (!s || !v) throw new EditError(`no measured variable "${p.name}"`);
      if (newName === v.name) return model;
      if (s.variables.some((x) => x.name === newName)) throw new EditError(`"${s.name}" measures "${newName}" already`);
      renameTopics(m, new Map([[topicName(drone, s.name, v.name), topicName(drone, s.name, newName)]]));
      v.name = newName;
      moveLayoutKeys(m, [[id, topicId(s.name, newName)]]);
      return m;
    }
    case "publisher": case "subscriber": {
      const list: Array<Publisher | Subscriber> = p.kind === "publisher" ? m.publishers : m.subscribers;
      const x = list.find((e) => e.name === p.name);
      if (!x) throw new EditError(`no ${p.kind} "${p.name}"`);
      if (newName === x.name) return model;
      if (clientNames(m).includes(newName)) throw new EditError(`"${newName}" names a publisher or subscriber already`);
      x.name = newName;
      const newId = p.kind === "publisher" ? publisherId(newName) : subscriberId(newName);
      moveLayoutKeys(m, [[id, newId]]);
      return m;
    }
  }
}

/** The id an element has after `rename(model, id, newName)`. */
export function renamedId(id: string, newName: string): string {
  const p = parseId(id);
  switch (p?.kind) {
    case "sensor": return sensorId(newName);
    case "topic": return topicId(p.sensor!, newName);
    case "publisher": return publisherId(newName);
    case "subscriber": return subscriberId(newName);
    default: return id;
  }
}

/** The model object an element id designates (for the inspector), or undefined. */
export function elementValue(model: ModdModel, id: string): object | undefined {
  const p = parseId(id);
  switch (p?.kind) {
    case "drone": return model.drone;
    case "pubBroker": return model.pubBroker;
    case "subBroker": return model.subBroker;
    case "link": return model.link ?? {};
    case "sensor": return model.drone.sensors.find((s) => s.name === p.sensor);
    case "topic": return listTopics(model).find((t) => t.id === id)?.variable;
    case "publisher": return model.publishers.find((x) => x.name === p.name);
    case "subscriber": return model.subscribers.find((x) => x.name === p.name);
    default: return undefined;
  }
}

/**
 * Sets (or, with `undefined`, removes) a field inside an element, by path.
 * Names go through `rename` so references follow.
 *
 * @example setField(m, "sub:sub_1", ["periodS"], "0.25")
 */
export function setField(model: ModdModel, id: string, path: string[], value: unknown): ModdModel {
  if (path.length === 1 && path[0] === "name" && id !== PUB_BROKER_ID && id !== SUB_BROKER_ID) {
    if (typeof value !== "string") throw new EditError("a name is text");
    return rename(model, id, value);
  }
  if (path.length === 0) throw new EditError("no field given");
  const m = clone(model);
  if (id === LINK_ID && !m.link) m.link = {};
  const target = elementValue(m, id) as Record<string, unknown> | undefined;
  if (!target) throw new EditError(`unknown element "${id}"`);
  setIn(target, path, value);
  if (id === LINK_ID && m.link && Object.keys(m.link).length === 0) delete m.link;
  return m;
}

/**
 * Sets `value` at `path` inside `target` (changed in place), making the nested
 * objects on the way; `undefined` removes the field and the nested objects it
 * leaves empty (a source's condition whose parts are all cleared). Array
 * items are addressed by their index ("0").
 */
export function setIn(target: Record<string, unknown>, path: readonly string[], value: unknown): void {
  const chain: Record<string, unknown>[] = [target];
  for (const seg of path.slice(0, -1)) {
    const obj = chain[chain.length - 1];
    if (typeof obj[seg] !== "object" || obj[seg] === null) obj[seg] = {};
    chain.push(obj[seg] as Record<string, unknown>);
  }
  const last = path[path.length - 1];
  if (value === undefined) {
    delete chain[chain.length - 1][last];
    for (let i = chain.length - 1; i > 0 && Object.keys(chain[i]).length === 0; i--) delete chain[i - 1][path[i - 1]];
  } else chain[chain.length - 1][last] = value;
}

/** Saves node positions into the layout. */
export function moveNodes(model: ModdModel, positions: Record<string, Position>): ModdModel {
  const m = clone(model);
  const rounded: Record<string, Position> = {};
  for (const [id, p] of Object.entries(positions)) rounded[id] = { x: Math.round(p.x), y: Math.round(p.y) };
  m.layout = { ...(m.layout ?? {}), nodes: { ...(m.layout?.nodes ?? {}), ...rounded } };
  return m;
}

export const SINGLETONS = [DRONE_ID, PUB_BROKER_ID, SUB_BROKER_ID, LINK_ID];
