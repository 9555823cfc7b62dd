/**
 * Read-only look-ups on a model: find elements by id, list topics, map JSON
 * pointers (as carried by validation diagnostics) to diagram elements.
 */
import type { ModdModel, MeasuredVariable, Sensor } from "./model.gen";
import {
  DRONE_ID, LINK_ID, PUB_BROKER_ID, SUB_BROKER_ID,
  parseId, publisherId, sensorId, subscriberId, topicId, topicName,
} from "./ids";

export interface TopicRef {
  /** Element id (`topic:sensor.variable`). */
  id: string;
  /** Fully qualified name `drone.sensor.variable`. */
  name: string;
  sensor: Sensor;
  variable: MeasuredVariable;
  sensorIndex: number;
  variableIndex: number;
}

/** Every measured variable of the drone, in model order. */
export function listTopics(model: ModdModel): TopicRef[] {
  const out: TopicRef[] = [];
  model.drone.sensors.forEach((sensor, si) =>
    sensor.variables.forEach((variable, vi) =>
      out.push({
        id: topicId(sensor.name, variable.name),
        name: topicName(model.drone.name, sensor.name, variable.name),
        sensor, variable, sensorIndex: si, variableIndex: vi,
      }),
    ),
  );
  return out;
}

/** The topic with this fully qualified name, if the model has it. */
export function findTopicByName(model: ModdModel, name: string): TopicRef | undefined {
  return listTopics(model).find((t) => t.name === name);
}

/** JSON pointer of the element with this id, or null when it does not exist. */
export function pointerOf(model: ModdModel, id: string): string | null {
  const p = parseId(id);
  if (!p) return null;
  switch (p.kind) {
    case "drone": return "/drone";
    case "pubBroker": return "/pubBroker";
    case "subBroker": return "/subBroker";
    case "link": return "/link";
    case "sensor": {
      const i = model.drone.sensors.findIndex((s) => s.name === p.sensor);
      return i < 0 ? null : `/drone/sensors/${i}`;
    }
    case "topic": {
      const t = listTopics(model).find((x) => x.id === id);
      return t ? `/drone/sensors/${t.sensorIndex}/variables/${t.variableIndex}` : null;
    }
    case "publisher": {
      const i = model.publishers.findIndex((x) => x.name === p.name);
      return i < 0 ? null : `/publishers/${i}`;
    }
    case "subscriber": {
      const i = model.subscribers.findIndex((x) => x.name === p.name);
      return i < 0 ? null : `/subscribers/${i}`;
    }
  }
}

export interface PointerTarget {
  /** The diagram element the pointer falls in. */
  id: string;
  /** The rest of the pointer inside the element, as path segments (e.g. ["endpoint", "port"]). */
  field: string[];
}

function unescape(seg: string): string {
  return seg.replace(/~1/g, "/").replace(/~0/g, "~");
}

/**
 * Maps a JSON pointer (RFC 6901) to the diagram element that holds it and the
 * field path inside that element. Pointers at the document root map to the drone.
 *
 * @example pointerTarget(m, "/subscribers/2/periodS") // { id: "sub:sub_3", field: ["periodS"] }
 */
export function pointerTarget(model: ModdModel, pointer: string): PointerTarget {
  const segs = pointer.split("/").slice(1).map(unescape);
  const [head, a, b, c, d, ...rest] = segs;
  switch (head) {
    case "drone": {
      if (a === "sensors" && b !== undefined) {
        const sensor = model.drone.sensors[Number(b)];
        if (!sensor) return { id: DRONE_ID, field: ["sensors"] };
        if (c === "variables" && d !== undefined) {
          const v = sensor.variables[Number(d)];
          if (v) return { id: topicId(sensor.name, v.name), field: rest };
        }
        return { id: sensorId(sensor.name), field: segs.slice(3) };
      }
      return { id: DRONE_ID, field: segs.slice(1) };
    }
    case "pubBroker": return { id: PUB_BROKER_ID, field: segs.slice(1) };
    case "subBroker": return { id: SUB_BROKER_ID, field: segs.slice(1) };
    case "link": return { id: LINK_ID, field: segs.slice(1) };
    case "publishers": {
      const x = a !== undefined ? model.publishers[Number(a)] : undefined;
      return x ? { id: publisherId(x.name), field: segs.slice(2) } : { id: DRONE_ID, field: segs };
    }
    case "subscribers": {
      const x = a !== undefined ? model.subscribers[Number(a)] : undefined;
      return x ? { id: subscriberId(x.name), field: segs.slice(2) } : { id: DRONE_ID, field: segs };
    }
    default:
      return { id: DRONE_ID, field: segs };
  }
}
