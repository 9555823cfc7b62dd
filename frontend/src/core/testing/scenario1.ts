/**
 * Scenario 1 of the paper (metamodel/tests/data/scenario1_datacollector.modd)
 * as a model document, for tests. Its plan has buffer sizes 28, 28, 6.
 */
import type { ModdModel } from "../model.gen";

export function scenario1(): ModdModel {
  const t = (v: string) => `usv.accelerometer.${v}`;
  const sub = (n: number, v: string, periodS: string, aggregation: "AVERAGE" | "MIN" | "MAX") => ({
    name: `sub_${n}`, endpoint: { host: "127.0.0.1", port: 7400 + n }, topic: t(v), periodS, aggregation,
  });
  return {
    schemaVersion: "1.0",
    drone: {
      name: "usv",
      sensors: [{
        name: "accelerometer",
        variables: ["accel_x", "accel_y", "accel_z"].map((name) => ({ name, unit: "METER_PER_SECOND_SQUARED" })),
      }],
    },
    pubBroker: { endpoint: { host: "127.0.0.1", port: 7171 }, logPath: "/tmp/modd/logs" },
    subBroker: { endpoint: { host: "127.0.0.1", port: 7272 }, configPath: "/tmp/modd/conf" },
    publishers: [{
      name: "pub_1", endpoint: { host: "127.0.0.1", port: 7373 }, periodS: "0.04",
      topics: [t("accel_x"), t("accel_y"), t("accel_z")],
    }],
    subscribers: [
      sub(1, "accel_x", "2.0", "AVERAGE"), sub(2, "accel_y", "2.0", "AVERAGE"),
      sub(3, "accel_x", "0.25", "AVERAGE"), sub(4, "accel_y", "0.25", "AVERAGE"),
      sub(5, "accel_z", "0.25", "MIN"), sub(6, "accel_z", "0.25", "MAX"), sub(7, "accel_z", "0.25", "MAX"),
    ],
  };
}
