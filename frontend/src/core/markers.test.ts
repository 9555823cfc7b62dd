import { describe, expect, it } from "vitest";
import { nodeMarkers } from "./markers";
import { scenario1 } from "./testing/scenario1";
import planJson from "./testing/scenario1.plan.json";
import type { PlanJson } from "./plan";

describe("nodeMarkers", () => {
  it("shows buffer sizes on topics and delays on subscribers", () => {
    const m = nodeMarkers(scenario1(), [], planJson as unknown as PlanJson);
    expect(m.get("topic:accelerometer.accel_x")?.badge).toBe("n = 28");
    expect(m.get("topic:accelerometer.accel_z")?.badge).toBe("n = 6");
    expect(m.get("sub:sub_1")?.badge).toBe("delay 0.88 s");
  });

  it("collects diagnostics once per element, and infeasibility", () => {
    const plan = { ...(planJson as unknown as PlanJson), infeasible: [{ topic: "usv.accelerometer.accel_y", subscribers: ["sub_2"], reason: "too fast" }] };
    const d = { severity: "error" as const, message: "bad period", pointer: "/subscribers/1/periodS" };
    const m = nodeMarkers(scenario1(), [d, d, { severity: "warning", message: "w", pointer: "/subscribers/1" }], plan);
    expect(m.get("sub:sub_2")).toMatchObject({ errors: ["bad period"], warnings: ["w"], infeasible: ["too fast"] });
    expect(m.get("topic:accelerometer.accel_y")?.infeasible).toEqual(["too fast"]);
  });
});
