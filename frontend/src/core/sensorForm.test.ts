import { describe, expect, it } from "vitest";
import { parseVariables, withSensor } from "./sensorForm";
import { emptyModel } from "./templates";
import { listTopics } from "./query";

describe("sensor form", () => {
  it("reads several variables, each with the form's unit or its own", () => {
    const { variables, bad } = parseVariables("accel_x, accel_y accel_z", "METER_PER_SECOND_SQUARED");
    expect(bad).toEqual([]);
    expect(variables.map((v) => `${v.name} ${v.unit}`)).toEqual([
      "accel_x METER_PER_SECOND_SQUARED", "accel_y METER_PER_SECOND_SQUARED", "accel_z METER_PER_SECOND_SQUARED"]);
    expect(parseVariables("temp:DEGREE_CELSIUS cond:mS/cm", "").variables).toEqual([
      { name: "temp", unit: "DEGREE_CELSIUS" }, { name: "cond", unit: "mS/cm" }]);
    expect(parseVariables("ok 9bad ok", "NONE").bad).toEqual(["9bad", "ok"]);
  });

  it("adds the sensor and all its variables in one model", () => {
    const m = withSensor(emptyModel(), "accelerometer", parseVariables("accel_x accel_y accel_z", "METER_PER_SECOND_SQUARED").variables);
    expect(listTopics(m).map((t) => t.name)).toEqual(["usv.accelerometer.accel_x", "usv.accelerometer.accel_y", "usv.accelerometer.accel_z"]);
    expect(() => withSensor(m, "accelerometer", [{ name: "x", unit: "NONE" }])).toThrow(/exists/);
    expect(() => withSensor(m, "ctd", [])).toThrow(/at least one/);
  });
});
