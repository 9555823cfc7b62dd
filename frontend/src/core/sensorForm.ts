/**
 * A sensor with several variables in one form (integrator): a name, the
 * variables as "accel_x, accel_y, accel_z" (each may carry its own unit:
 * "temp:DEGREE_CELSIUS, cond:mS/cm") and a unit for those without one.
 * Pure: the form's reading and the model with the sensor added (one edit).
 *
 * @example
 *   parseVariables("accel_x, accel_y", "METER_PER_SECOND_SQUARED").variables
 *   // [{ name: "accel_x", unit: "METER_PER_SECOND_SQUARED" }, { name: "accel_y", unit: ... }]
 */
import type { ModdModel, Position } from "./model.gen";
import { EditError, NAME_PATTERN, addSensor } from "./ops";

export interface NewVariable { name: string; unit: string }

/** The variables written in the form, and the words that are not names (or repeat one). */
export function parseVariables(text: string, unit: string): { variables: NewVariable[]; bad: string[] } {
  const variables: NewVariable[] = [];
  const bad: string[] = [];
  for (const word of text.split(/[\s,;]+/).filter(Boolean)) {
    const [name, own] = word.split(/:(.*)/s, 2);
    if (!NAME_PATTERN.test(name) || variables.some((v) => v.name === name)) bad.push(word);
    else variables.push({ name, unit: own || unit || "NONE" });
  }
  return { variables, bad };
}

/** The model with a sensor `name` measuring `variables` (throws EditError on a taken or bad name). */
export function withSensor(model: ModdModel, name: string, variables: NewVariable[], pos?: Position): ModdModel {
  if (!variables.length) throw new EditError("a sensor measures at least one variable");
  const { model: m } = addSensor(model, name, pos);
  const sensor = m.drone.sensors.find((s) => s.name === name)!;
  sensor.variables = variables.map((v) => ({ name: v.name, unit: v.unit }));
  return m;
}
