/**
 * Copy and paste of diagram elements. A fragment holds copies of sensors (with
 * their variables), publishers and subscribers, and their positions; pasting
 * gives each a free name and shifts it so it does not cover the original.
 * Topic references inside the fragment follow renamed sensors.
 *
 * @example
 *   const f = copyElements(model, ["sub:sub_1"]);
 *   const { model: m2, ids } = pasteFragment(model, f); // ids: ["sub:sub_1_copy"]
 */
import type { ModdModel, Position, Publisher, Sensor, Subscriber } from "./model.gen";
import { parseId, publisherId, sensorId, subscriberId, topicId, topicName } from "./ids";
import { uniqueName } from "./templates";

export interface Fragment {
  /** Drone the topic names of the fragment refer to. */
  drone: string;
  sensors: Sensor[];
  publishers: Publisher[];
  subscribers: Subscriber[];
  positions: Record<string, Position>;
}

export const PASTE_OFFSET = 40;

export function copyElements(model: ModdModel, ids: string[]): Fragment {
  const f: Fragment = { drone: model.drone.name, sensors: [], publishers: [], subscribers: [], positions: {} };
  const layout = model.layout?.nodes ?? {};
  const keep = (id: string) => { if (layout[id]) f.positions[id] = layout[id]; };
  for (const id of ids) {
    const p = parseId(id);
    if (p?.kind === "sensor") {
      const s = model.drone.sensors.find((x) => x.name === p.sensor);
      if (s) {
        f.sensors.push(structuredClone(s));
        keep(id);
        s.variables.forEach((v) => keep(topicId(s.name, v.name)));
      }
    } else if (p?.kind === "publisher") {
      const x = model.publishers.find((e) => e.name === p.name);
      if (x) { f.publishers.push(structuredClone(x)); keep(id); }
    } else if (p?.kind === "subscriber") {
      const x = model.subscribers.find((e) => e.name === p.name);
      if (x) { f.subscribers.push(structuredClone(x)); keep(id); }
    }
  }
  return f;
}

export const isEmptyFragment = (f: Fragment): boolean =>
  f.sensors.length + f.publishers.length + f.subscribers.length === 0;

function shifted(p: Position | undefined): Position | undefined {
  return p ? { x: p.x + PASTE_OFFSET, y: p.y + PASTE_OFFSET } : undefined;
}

export function pasteFragment(model: ModdModel, fragment: Fragment): { model: ModdModel; ids: string[] } {
  const m = structuredClone(model);
  const ids: string[] = [];
  const nodes = { ...(m.layout?.nodes ?? {}) };
  const place = (oldId: string, newId: string) => {
    const p = shifted(fragment.positions[oldId]);
    if (p) nodes[newId] = p;
  };
  // Topic names of the fragment → topic names in the target model.
  const topicMap = new Map<string, string>();
  const sensorNames = m.drone.sensors.map((s) => s.name);
  for (const s of fragment.sensors) {
    const name = uniqueName(s.name, sensorNames);
    sensorNames.push(name);
    m.drone.sensors.push({ ...structuredClone(s), name });
    ids.push(sensorId(name));
    place(sensorId(s.name), sensorId(name));
    for (const v of s.variables) {
      topicMap.set(topicName(fragment.drone, s.name, v.name), topicName(m.drone.name, name, v.name));
      place(topicId(s.name, v.name), topicId(name, v.name));
    }
  }
  const mapTopic = (t: string) => topicMap.get(t) ?? t;
  const clients = [...m.publishers.map((p) => p.name), ...m.subscribers.map((s) => s.name)];
  for (const p of fragment.publishers) {
    const name = uniqueName(p.name, clients);
    clients.push(name);
    m.publishers.push({ ...structuredClone(p), name, topics: p.topics.map(mapTopic) });
    ids.push(publisherId(name));
    place(publisherId(p.name), publisherId(name));
  }
  for (const s of fragment.subscribers) {
    const name = uniqueName(s.name, clients);
    clients.push(name);
    m.subscribers.push({ ...structuredClone(s), name, topic: mapTopic(s.topic) });
    ids.push(subscriberId(name));
    place(subscriberId(s.name), subscriberId(name));
  }
  m.layout = { ...(m.layout ?? {}), nodes };
  return { model: m, ids };
}
