import { describe, expect, it } from "vitest";
import { describeChanges, fieldInWords, valueInWords } from "./changeWords";
import { planChanges } from "./planDiff";
import { diagnosticsInWords } from "./diagnosticWords";
import { scenario1 } from "./testing/scenario1";
import planJson from "./testing/scenario1.plan.json";
import type { PlanJson } from "./plan";

describe("describeChanges", () => {
  it("tells an added subscriber, a changed period and a new publisher topic in words", () => {
    const before = scenario1();
    const after = structuredClone(before);
    after.subscribers.push({ name: "sub_8", topic: "usv.accelerometer.accel_x", periodS: "5", aggregation: "AVERAGE" });
    after.subscribers[6].periodS = "0.5";
    after.subscribers.splice(0, 1);
    const texts = describeChanges(before, after).map((c) => c.text);
    expect(texts).toContain("subscriber sub_8 added: usv.accelerometer.accel_x (m/s²) AVERAGE every 5 s");
    expect(texts).toContain("subscriber sub_7: period 0.25 s → 0.5 s");
    expect(texts.some((t) => /^subscriber sub_1 removed/.test(t))).toBe(true);
    expect(texts.join("\n")).not.toMatch(/\/subscribers/);
  });

  it("lists each element once when nothing is deployed", () => {
    const texts = describeChanges({}, scenario1()).map((c) => c.text);
    expect(texts).toContain("sensor accelerometer added: usv.accelerometer.accel_x (m/s²), usv.accelerometer.accel_y (m/s²), usv.accelerometer.accel_z (m/s²)");
    expect(texts.filter((t) => t.startsWith("subscriber "))).toHaveLength(7);
  });

  it("ignores the layout", () => {
    const a = scenario1();
    const b = { ...structuredClone(a), layout: { nodes: { drone: { x: 1, y: 2 } } } };
    expect(describeChanges(a, b)).toEqual([]);
  });
});

describe("planChanges", () => {
  it("gives hyperperiod and delays before → after, nothing for an equal plan", () => {
    const a = planJson as unknown as PlanJson;
    expect(planChanges(a, a)).toEqual([]);
    const b = { ...a, hyperperiod_s: "10.0", delays: { ...a.delays, sub_1: "2.0" } };
    const c = planChanges(a, b);
    expect(c.find((x) => x.key === "hyperperiod")).toMatchObject({ before: "2.0 s", after: "10.0 s" });
    expect(c.find((x) => x.key === "delay:sub_1")).toMatchObject({ after: "2.0 s" });
    expect(c).toHaveLength(2);
  });
});

describe("diagnosticsInWords", () => {
  it("names the element and drops duplicates", () => {
    const m = scenario1();
    const d = diagnosticsInWords(m, [
      { severity: "error", message: "required", pointer: "/subscribers/6/topic" },
      { severity: "error", message: "required", pointer: "/subscribers/6/topic", source: "local" },
      { severity: "warning", message: "odd", pointer: "/drone/sensors/0/variables/1/unit" },
    ]);
    expect(d.map((x) => `${x.element}: ${x.text}`)).toEqual(["subscriber sub_7: topic: required", "variable accelerometer.accel_y: unit: odd"]);
  });
});

describe("fieldInWords", () => {
  it("names a field by its element and the model's word, and shows its value with its unit", () => {
    expect(fieldInWords("/subscribers/sub_7/periodS")).toBe("subscriber sub_7: period");
    expect(valueInWords("/subscribers/sub_7/periodS", "5")).toBe("5 s");
    expect(fieldInWords("/drone/sensors/ctd/variables/water_temperature/unit")).toBe("variable ctd.water_temperature: unit");
    expect(fieldInWords("/publishers/pub_1/topics")).toBe("publisher pub_1: topics");
    expect(valueInWords("/publishers/pub_1/topics", ["a", "b"])).toBe("a, b");
    expect(fieldInWords("/subscribers/sub_2")).toBe("subscriber sub_2");
    expect(valueInWords("/subscribers/sub_2", { name: "sub_2", topic: "usv.gps.lat", periodS: "1.0", aggregation: "LAST" }))
      .toBe("usv.gps.lat LAST every 1.0 s");
    expect(valueInWords("/subscribers/sub_2", undefined)).toBe("(removed)");
  });
});
