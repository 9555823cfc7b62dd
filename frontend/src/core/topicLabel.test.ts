import { describe, expect, it } from "vitest";
import { aggregationLabel, subscriptionLabel, topicLabel } from "./topicLabel";
import { planFigures } from "./planDiff";
import type { PlanJson } from "./plan";
import type { ModdModel } from "./model.gen";

const model = {
  schemaVersion: "1.0",
  drone: { name: "usv", sensors: [
    { name: "accelerometer", variables: [{ name: "accel_x", unit: "METER_PER_SECOND_SQUARED" }] },
    { name: "gps", variables: [{ name: "latitude", unit: "NONE" }] },
  ] },
  publishers: [], subscribers: [],
} as unknown as ModdModel;

describe("topicLabel", () => {
  it("adds the unit as the quick subscription shows it", () => {
    expect(topicLabel(model, "usv.accelerometer.accel_x")).toBe("usv.accelerometer.accel_x (m/s²)");
  });
  it("shows the name alone without a unit or outside the model", () => {
    expect(topicLabel(model, "usv.gps.latitude")).toBe("usv.gps.latitude");
    expect(topicLabel(model, "usv.gone.x")).toBe("usv.gone.x");
    expect(topicLabel(undefined, "usv.gone.x")).toBe("usv.gone.x");
  });
  it("looks in the models in order (a removed topic keeps its unit)", () => {
    expect(topicLabel([undefined, model], "usv.accelerometer.accel_x")).toBe("usv.accelerometer.accel_x (m/s²)");
  });
  it("tells a subscription", () => {
    expect(subscriptionLabel(model, { topic: "usv.accelerometer.accel_x", aggregation: "MIN", periodS: "0.25" }))
      .toBe("usv.accelerometer.accel_x (m/s²) MIN every 0.25 s");
    expect(subscriptionLabel(model, { topic: "", aggregation: "MIN", periodS: "1" })).toBe("(no topic) MIN every 1 s");
    // a percentile by its label, as the plan and the delivered values name it
    expect(subscriptionLabel(model, { topic: "usv.accelerometer.accel_x", aggregation: "PERCENTILE", percentile: 99.5, periodS: "2.0" }))
      .toBe("usv.accelerometer.accel_x (m/s²) PERCENTILE(99.5) every 2.0 s");
    // event subscriptions by their label: parameters, then N when declared
    expect(aggregationLabel({ aggregation: "ON_CHANGE", deadband: 0.5, maxEvents: 4 })).toBe("ON_CHANGE(0.5, 4)");
    expect(aggregationLabel({ aggregation: "ON_CHANGE", deadbandPercent: 5 })).toBe("ON_CHANGE(5%)");
    expect(aggregationLabel({ aggregation: "THRESHOLD", level: 5, hysteresis: 0.2, crossing: "down" })).toBe("THRESHOLD(DOWN 5, 0.2)");
    expect(aggregationLabel({ aggregation: "THRESHOLD", level: -2 })).toBe("THRESHOLD(BOTH -2)");
  });
});

describe("plan figures name topics as the workbench does", () => {
  it("labels a buffer size with the topic's unit", () => {
    const plan = { hyperperiod_s: "2.0", messages_per_hyperperiod: 8, predicted_link_bytes_per_s: { drone_to_base: 10 }, max_delay_s: "0",
      delays: {}, buffer_sizes: { "usv.accelerometer.accel_x": 28 } } as unknown as PlanJson;
    expect(planFigures(plan, (t) => topicLabel(model, t)).get("buffer:usv.accelerometer.accel_x"))
      .toEqual(["usv.accelerometer.accel_x (m/s²) buffer", "28"]);
  });
});
