/**
 * Model → diagram graph. Pure data: the editor turns it into xyflow nodes and
 * edges, adding React-only concerns (selection, handlers).
 *
 * Nodes: the drone, its sensors, their measured variables (topics), the two
 * brokers, publishers and subscribers. Edges: drone → sensor and
 * sensor → topic (structure, not editable), publisher → topic and
 * topic → subscriber (data flow, editable by connecting handles), and
 * PubBroker → SubBroker (the link).
 *
 * Positions come from `model.layout.nodes` by element id; elements without a
 * saved position get a deterministic column layout (see `defaultPosition`).
 */
import type { ModdModel, Position } from "./model.gen";
import type { ElementKind } from "./ids";
import {
  DRONE_ID, LINK_ID, PUB_BROKER_ID, SUB_BROKER_ID,
  publisherId, sensorId, subscriberId,
} from "./ids";
import { listTopics } from "./query";
import { subscriptionLabel, topicLabel } from "./topicLabel";

export type EdgeKind = "carries" | "measures" | "publishes" | "subscribes" | "link";

export interface GraphNode {
  id: string;
  kind: ElementKind;
  label: string;
  /** Second line: unit, period/aggregation, endpoint… */
  detail: string;
  position: Position;
}

export interface GraphEdge {
  id: string;
  kind: EdgeKind;
  source: string;
  target: string;
}

export interface Graph {
  nodes: GraphNode[];
  edges: GraphEdge[];
}

/** Column (x) of each kind in the default layout, left to right as data flows. */
const COLUMN: Record<ElementKind, number> = {
  drone: 0, publisher: 0, pubBroker: 0,
  sensor: 1, link: 1,
  topic: 2,
  subscriber: 3, subBroker: 3,
};
export const COLUMN_WIDTH = 260;
export const ROW_HEIGHT = 80;

/** Position of the `row`-th element of a kind when the layout does not have one. */
export function defaultPosition(kind: ElementKind, row: number): Position {
  const brokerOffset = kind === "pubBroker" || kind === "subBroker" ? -1 : 0;
  return { x: COLUMN[kind] * COLUMN_WIDTH, y: (row + brokerOffset) * ROW_HEIGHT + (kind === "publisher" ? ROW_HEIGHT : 0) };
}

export const edgeId = (kind: EdgeKind, source: string, target: string): string =>
  kind === "link" ? LINK_ID : `${kind}:${source}->${target}`;

/** Builds the diagram graph of a model. */
export function modelToGraph(model: ModdModel): Graph {
  const saved = model.layout?.nodes ?? {};
  const nodes: GraphNode[] = [];
  const edges: GraphEdge[] = [];
  const rows: Partial<Record<ElementKind, number>> = {};
  const add = (id: string, kind: ElementKind, label: string, detail: string) => {
    const row = rows[kind] ?? 0;
    rows[kind] = row + 1;
    nodes.push({ id, kind, label, detail, position: saved[id] ?? defaultPosition(kind, row) });
  };

  add(DRONE_ID, "drone", model.drone.name, `${model.drone.sensors.length} sensor(s)`);
  const pb = model.pubBroker;
  add(PUB_BROKER_ID, "pubBroker", pb.name ?? "PubBroker", `${pb.endpoint.host}:${pb.endpoint.port}`);
  const sb = model.subBroker;
  add(SUB_BROKER_ID, "subBroker", sb.name ?? "SubBroker", `${sb.endpoint.host}:${sb.endpoint.port}`);
  edges.push({ id: LINK_ID, kind: "link", source: PUB_BROKER_ID, target: SUB_BROKER_ID });

  for (const sensor of model.drone.sensors) {
    const sid = sensorId(sensor.name);
    add(sid, "sensor", sensor.name, `${sensor.variables.length} variable(s)`);
    edges.push({ id: edgeId("carries", DRONE_ID, sid), kind: "carries", source: DRONE_ID, target: sid });
  }
  const byName = new Map<string, string>();
  for (const t of listTopics(model)) {
    add(t.id, "topic", t.variable.name, `${topicLabel(model, t.name)} · ${t.variable.type ?? "float32"}`);
    byName.set(t.name, t.id);
    const sid = sensorId(t.sensor.name);
    edges.push({ id: edgeId("measures", sid, t.id), kind: "measures", source: sid, target: t.id });
  }
  for (const p of model.publishers) {
    const pid = publisherId(p.name);
    add(pid, "publisher", p.name, `every ${p.periodS} s`);
    for (const topic of p.topics) {
      const tid = byName.get(topic);
      if (tid) edges.push({ id: edgeId("publishes", pid, tid), kind: "publishes", source: pid, target: tid });
    }
  }
  for (const s of model.subscribers) {
    const sid = subscriberId(s.name);
    add(sid, "subscriber", s.name, subscriptionLabel(model, s));
    const tid = byName.get(s.topic);
    if (tid) edges.push({ id: edgeId("subscribes", tid, sid), kind: "subscribes", source: tid, target: sid });
  }
  return { nodes, edges };
}

/** Kinds of the elements an edge of this kind may join, for connection checks. */
export const CONNECTABLE: Partial<Record<EdgeKind, [ElementKind, ElementKind]>> = {
  publishes: ["publisher", "topic"],
  subscribes: ["topic", "subscriber"],
};

/**
 * Where to put a new element of `kind`: in its column, one row below the
 * lowest element of that kind already placed (saved or default position).
 */
export function nextPosition(model: ModdModel, kind: ElementKind): Position {
  const same = modelToGraph(model).nodes.filter((n) => n.kind === kind);
  if (same.length === 0) return defaultPosition(kind, 0);
  const lowest = same.reduce((a, b) => (b.position.y > a.position.y ? b : a));
  return { x: lowest.position.x, y: lowest.position.y + ROW_HEIGHT };
}
