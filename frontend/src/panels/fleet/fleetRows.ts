/**
 * What the fleet view says of each drone, from its status document (the
 * SubBroker's, docs/subbroker.md "Status") and this project's deployments:
 * link state, serving station, the last window's age, the instruments'
 * health, and the revision a rollback would go back to.
 *
 * @example
 *   droneRow({ name: "usv1", status: { link: "up", station: "a", time_ns: 5e9, last_data_ns: 4e9, sensors: {} }, ... })
 *   // { name: "usv1", link: "up", station: "a", lastWindowAgeS: 1, instruments: "none reported", ... }
 */
import type { Deployment, FleetDrone } from "../../api/types";
import type { SensorHealth } from "../../core/contracts.gen";
import { instrumentsHealth } from "../../core/instrumentHealth";

export interface DroneRow {
  name: string;
  description: string | null;
  link: string | null;
  station: string | null;
  /** Seconds from the last DATA frame to the status that said so (null: none yet, or not reporting). */
  lastWindowAgeS: number | null;
  instruments: string;
  instrumentAlerts: string[];
  deployed: Deployment | null;
}

function num(v: unknown): number | null {
  return typeof v === "number" && Number.isFinite(v) ? v : null;
}

export function droneRow(d: FleetDrone): DroneRow {
  const s = d.status ?? {};
  const now = num(s.time_ns), last = num(s.last_data_ns);
  const health = instrumentsHealth((s.sensors ?? null) as Record<string, SensorHealth> | null);
  const alerts = health.filter((h) => h.alert).map((h) => `${h.name}: ${h.alert}`);
  return {
    name: d.name,
    description: d.description,
    link: d.status ? String(s.link ?? "unknown") : null,
    station: typeof s.station === "string" ? s.station : null,
    lastWindowAgeS: now !== null && last !== null && last > 0 ? Math.max(0, (now - last) / 1e9) : null,
    instruments: !d.status ? "not reporting" : health.length === 0 ? "none reported"
      : `${health.length - alerts.length} of ${health.length} well`,
    instrumentAlerts: alerts,
    deployed: d.deployment,
  };
}

/** The revision to roll a drone back to: the last acked revision before the one it runs (null: none). */
export function rollbackRevision(drone: string, history: readonly Deployment[]): number | null {
  const acked = history.filter((h) => h.drone === drone && h.status === "acked").sort((a, b) => b.id - a.id);
  if (!acked.length) return null;
  const current = acked[0].revision;
  return acked.find((h) => h.revision !== current)?.revision ?? null;
}

/** `sensor.variable` of each of the mission model's topics (what a fleet subscription names). */
export function fleetVariables(topics: readonly string[]): string[] {
  return topics.map((t) => t.split(".").slice(1).join("."));
}
