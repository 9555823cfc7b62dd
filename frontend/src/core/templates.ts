/**
 * New models and new elements with sensible defaults (loopback endpoints, the
 * paper's directories).
 */
import type { ModdModel } from "./model.gen";

/**
 * An empty project: a drone without sensors, both brokers on loopback, no
 * publishers, no subscribers.
 *
 * @example emptyModel("usv").drone.sensors.length // 0
 */
export function emptyModel(droneName = "usv"): ModdModel {
  return {
    schemaVersion: "1.0",
    drone: { name: droneName, sensors: [] },
    pubBroker: { endpoint: { host: "127.0.0.1", port: 7171 }, logPath: "/tmp/modd/logs" },
    subBroker: { endpoint: { host: "127.0.0.1", port: 7272 }, configPath: "/tmp/modd/conf" },
    publishers: [],
    subscribers: [],
    layout: { nodes: {} },
  };
}

/** `base_1`, `base_2`, … : the first name of that form not in `taken`. */
export function freshName(base: string, taken: Iterable<string>): string {
  const used = new Set(taken);
  for (let i = 1; ; i += 1) {
    const name = `${base}_${i}`;
    if (!used.has(name)) return name;
  }
}

/** A name not in `taken`: `name` itself if free, else `name_copy`, `name_copy_2`, … */
export function uniqueName(name: string, taken: Iterable<string>): string {
  const used = new Set(taken);
  if (!used.has(name)) return name;
  if (!used.has(`${name}_copy`)) return `${name}_copy`;
  for (let i = 2; ; i += 1) {
    const n = `${name}_copy_${i}`;
    if (!used.has(n)) return n;
  }
}
