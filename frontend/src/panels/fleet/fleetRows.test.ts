import { describe, expect, it } from "vitest";
import type { Deployment, FleetDrone } from "../../api/types";
import { droneRow, fleetVariables, rollbackRevision } from "./fleetRows";

const ENDS = { pub_broker: { endpoint: { host: "127.0.0.1", port: 7181 } }, sub_broker: { endpoint: { host: "127.0.0.1", port: 7272 } } };

function dep(id: number, drone: string, revision: number, status = "acked"): Deployment {
  return { id, project_id: 1, revision, drone, requested_by: "op", requested_at: "", finished_at: "", status, reply: null, error: null };
}

describe("droneRow", () => {
  it("reads the link, the station, the last window's age and the instruments from the status", () => {
    const d: FleetDrone = {
      name: "usv1", description: "North", channel: "ch1", ...ENDS, deployment: dep(3, "usv1", 2),
      status: {
        link: "up", station: "shore", time_ns: 10_500_000_000, last_data_ns: 8_000_000_000,
        sensors: { ctd: { state: 1, lines_ok: 9, lines_bad: 0, last_value_ms: 1 }, gnss: { state: 0, lines_ok: 0, lines_bad: 0 } },
      },
    };
    const row = droneRow(d);
    expect([row.link, row.station, row.lastWindowAgeS]).toEqual(["up", "shore", 2.5]);
    expect(row.instruments).toBe("1 of 2 well");
    expect(row.instrumentAlerts).toHaveLength(1);
    expect(row.instrumentAlerts[0]).toMatch(/^gnss: /);
    expect(row.deployed?.revision).toBe(2);
  });

  it("says a drone that does not report is not reporting", () => {
    const row = droneRow({ name: "usv2", description: null, channel: null, ...ENDS, deployment: null, status: null });
    expect([row.link, row.station, row.lastWindowAgeS, row.instruments]).toEqual([null, null, null, "not reporting"]);
  });
});

describe("rollbackRevision", () => {
  it("is the last acked revision before the one the drone runs, per drone", () => {
    const history = [dep(5, "usv1", 3), dep(4, "usv2", 3), dep(3, "usv1", 2, "failed"), dep(2, "usv1", 1), dep(1, "usv2", 3)];
    expect(rollbackRevision("usv1", history)).toBe(1);   // r2 failed: never ran
    expect(rollbackRevision("usv2", history)).toBeNull(); // only r3 ever ran
    expect(rollbackRevision("usv3", history)).toBeNull();
  });
});

describe("fleetVariables", () => {
  it("drops the mission drone's name", () => {
    expect(fleetVariables(["usv.ctd.water_temperature", "usv.gnss.lat"])).toEqual(["ctd.water_temperature", "gnss.lat"]);
  });
});
