/**
 * An empty project says which link ends the running drone uses (`make run`
 * moves them with MODD_PORT: 7181/7282 under 8090), and offers them as its
 * PubBroker and SubBroker endpoints. Pure: the hint and the edits to make.
 *
 * @example
 *   runningHint(emptyModel(), [{ drone: "usv", pub_broker: { host: "127.0.0.1", port: 7181 }, ... }])
 *   // { text: "The running drone usv uses PubBroker 127.0.0.1:7181 and SubBroker 127.0.0.1:7282.", edits: [...] }
 */
import type { RunningDrone } from "../api/types";
import { PUB_BROKER_ID, SUB_BROKER_ID } from "./ids";
import type { ModdModel } from "./model.gen";

export interface RunningHint {
  text: string;
  /** setField edits that give the model these endpoints (none when it has them already). */
  edits: Array<{ id: string; path: string[]; value: { host: string; port: number } }>;
}

const same = (a: { host: string; port: number }, b: { host: string; port: number }) => a.host === b.host && a.port === b.port;

/** The hint for a model with no sensor, publisher or subscriber yet; else null. */
export function runningHint(model: ModdModel, running: readonly RunningDrone[]): RunningHint | null {
  const empty = !model.drone.sensors.length && !model.publishers.length && !model.subscribers.length;
  const drone = running.find((d) => d.pub_broker && d.sub_broker);
  if (!empty || !drone?.pub_broker || !drone.sub_broker) return null;
  const ends = [[PUB_BROKER_ID, drone.pub_broker, model.pubBroker.endpoint], [SUB_BROKER_ID, drone.sub_broker, model.subBroker.endpoint]] as const;
  const at = (e: { host: string; port: number }) => `${e.host}:${e.port}`;
  return {
    text: `The running drone ${drone.drone} uses PubBroker ${at(drone.pub_broker)} and SubBroker ${at(drone.sub_broker)}.`,
    edits: ends.filter(([, theirs, ours]) => !same(theirs, ours)).map(([id, theirs]) => ({ id, path: ["endpoint"], value: { host: theirs.host, port: theirs.port } })),
  };
}
