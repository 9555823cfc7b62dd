import { describe, expect, it } from "vitest";
import { formatRate, infeasibleElements, timeline, topicRows, zoomWindow, type PlanJson } from "./plan";
import planJson from "./testing/scenario1.plan.json";
import { scenario1 } from "./testing/scenario1";

const plan = planJson as unknown as PlanJson;

describe("plan views", () => {
  it("gives buffer sizes 28, 28, 6 with each subscriber's delay", () => {
    const rows = topicRows(plan);
    expect(rows.map((r) => r.bufferSize)).toEqual([28, 28, 6]);
    expect(rows[0].subscribers).toEqual([
      { name: "sub_1", stream: "usv.accelerometer.accel_x/AVERAGE/2.0", delayS: "0.88" },
      { name: "sub_3", stream: "usv.accelerometer.accel_x/AVERAGE/0.25", delayS: "0.87" },
    ]);
    expect(rows[2].subscribers.map((s) => s.name)).toEqual(["sub_5", "sub_6", "sub_7"]);
  });

  it("places the slots of one hyperperiod on a timeline, zoomable", () => {
    const all = timeline(plan);
    expect(all).toHaveLength(8);
    expect(all[0]).toMatchObject({ slot: 0, t: 0.25, x: 0.125 });
    expect(all[0].streams).toContain("usv.accelerometer.accel_z/MIN/0.25");
    const zoomed = timeline(plan, 0.5, 1.0);
    expect(zoomed.map((m) => m.slot)).toEqual([1, 2, 3]);
    expect(zoomed[0].x).toBe(0);
    expect(zoomed[2].x).toBe(1);
  });

  it("keeps zoom windows inside the hyperperiod", () => {
    expect(zoomWindow(2, 0, 0.5)).toEqual([0, 0.5]);
    expect(zoomWindow(2, 2, 0.5)).toEqual([1.5, 2]);
    expect(zoomWindow(2, 1, 5)).toEqual([0, 2]);
  });

  it("explains infeasibility on the topic and subscriber nodes", () => {
    const p: PlanJson = { ...plan, infeasible: [{ topic: "usv.accelerometer.accel_z", subscribers: ["sub_5"], reason: "period shorter than publication" }] };
    const m = infeasibleElements(scenario1(), p);
    expect([...m.keys()]).toEqual(["topic:accelerometer.accel_z", "sub:sub_5"]);
    expect(m.get("sub:sub_5")).toEqual(["period shorter than publication"]);
  });

  it("formats rates", () => {
    expect(formatRate(296)).toBe("296 B/s");
    expect(formatRate(14875)).toBe("14.88 kB/s");
    expect(formatRate(2.5e6)).toBe("2.50 MB/s");
  });
});
