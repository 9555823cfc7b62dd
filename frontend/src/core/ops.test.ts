import { describe, expect, it } from "vitest";
import {
  EditError, addPublisher, addSensor, addSubscriber, addVariable, canConnect, connect, disconnect,
  moveNodes, removeElement, removeElements, rename, setField,
} from "./ops";
import { emptyModel } from "./templates";
import { scenario1 } from "./testing/scenario1";
import type { ModdModel } from "./model.gen";

/** Scenario 1 built by the same operations the palette and the canvas use. */
function buildScenario1(): ModdModel {
  let m = emptyModel("usv");
  m = addSensor(m, "accelerometer").model;
  m = rename(m, "topic:accelerometer.var_1", "accel_x");
  m = setField(m, "topic:accelerometer.accel_x", ["unit"], "METER_PER_SECOND_SQUARED");
  for (const v of ["accel_y", "accel_z"]) m = addVariable(m, "accelerometer", v, "METER_PER_SECOND_SQUARED").model;
  m = addPublisher(m, "pub_1", "0.04").model;
  m = setField(m, "pub:pub_1", ["endpoint"], { host: "127.0.0.1", port: 7373 });
  for (const v of ["accel_x", "accel_y", "accel_z"]) m = connect(m, "pub:pub_1", `topic:accelerometer.${v}`);
  const subs: Array<[string, string, "AVERAGE" | "MIN" | "MAX"]> = [
    ["accel_x", "2.0", "AVERAGE"], ["accel_y", "2.0", "AVERAGE"], ["accel_x", "0.25", "AVERAGE"],
    ["accel_y", "0.25", "AVERAGE"], ["accel_z", "0.25", "MIN"], ["accel_z", "0.25", "MAX"], ["accel_z", "0.25", "MAX"],
  ];
  subs.forEach(([v, periodS, aggregation], i) => {
    const r = addSubscriber(m, { periodS, aggregation });
    m = connect(r.model, `topic:accelerometer.${v}`, r.id);
    m = setField(m, r.id, ["endpoint"], { host: "127.0.0.1", port: 7401 + i });
  });
  return m;
}

describe("building a model by edits", () => {
  it("builds scenario 1 from an empty project", () => {
    const { layout, ...built } = buildScenario1();
    expect(layout).toEqual({ nodes: {} });
    expect(built).toEqual(scenario1());
  });

  it("never changes its input", () => {
    const m = scenario1();
    const copy = structuredClone(m);
    addSensor(m); addPublisher(m); addSubscriber(m); rename(m, "sensor:accelerometer", "acc");
    removeElement(m, "sub:sub_1"); connect(m, "topic:accelerometer.accel_z", "sub:sub_1");
    expect(m).toEqual(copy);
  });
});

describe("add", () => {
  it("gives fresh names and records positions", () => {
    let m = emptyModel();
    const a = addSensor(m, undefined, { x: 1, y: 2 });
    m = addSensor(a.model).model;
    expect(m.drone.sensors.map((s) => s.name)).toEqual(["sensor_1", "sensor_2"]);
    expect(m.drone.sensors[0].variables).toHaveLength(1);
    expect(m.layout?.nodes?.["sensor:sensor_1"]).toEqual({ x: 1, y: 2 });
  });

  it("shares one namespace between publishers and subscribers", () => {
    let m = addPublisher(emptyModel(), "sub_1").model;
    m = addSubscriber(m).model;
    expect(m.subscribers[0].name).toBe("sub_2");
    expect(() => addPublisher(m, "sub_2")).toThrow(EditError);
  });

  it("names a new sensor's first variable as + Variable names the next ones", () => {
    let m = addSensor(emptyModel()).model;
    m = addVariable(m, "sensor_1").model;
    m = addVariable(m, "sensor_1").model;
    expect(m.drone.sensors[0].variables.map((v) => v.name)).toEqual(["var_1", "var_2", "var_3"]);
  });

  it("refuses bad and duplicate names", () => {
    expect(() => addSensor(emptyModel(), "1bad")).toThrow(/not a name/);
    const m = addSensor(emptyModel(), "gps").model;
    expect(() => addSensor(m, "gps")).toThrow(/exists/);
    expect(() => addVariable(m, "gps", "var_1")).toThrow(/already/);
    expect(() => addVariable(m, "nope")).toThrow(/no sensor/);
  });
});

describe("connect", () => {
  const m = scenario1();
  it("accepts only publisher → topic and topic → subscriber", () => {
    expect(canConnect(m, "topic:accelerometer.accel_z", "sub:sub_1")).toBe(true);
    expect(canConnect(m, "sub:sub_1", "topic:accelerometer.accel_z")).toBe(false);
    expect(canConnect(m, "pub:pub_1", "sub:sub_1")).toBe(false);
    expect(canConnect(m, "drone", "sensor:accelerometer")).toBe(false);
    // Already connected.
    expect(canConnect(m, "pub:pub_1", "topic:accelerometer.accel_x")).toBe(false);
  });

  it("replaces a subscriber's topic", () => {
    const n = connect(m, "topic:accelerometer.accel_z", "sub:sub_1");
    expect(n.subscribers[0].topic).toBe("usv.accelerometer.accel_z");
  });

  it("disconnects both kinds", () => {
    const n = disconnect(disconnect(m, "pub:pub_1", "topic:accelerometer.accel_y"), "topic:accelerometer.accel_x", "sub:sub_1");
    expect(n.publishers[0].topics).toEqual(["usv.accelerometer.accel_x", "usv.accelerometer.accel_z"]);
    expect(n.subscribers[0].topic).toBe("");
    expect(() => disconnect(m, "drone", "pubBroker")).toThrow(EditError);
  });
});

describe("remove", () => {
  it("removes a sensor with its topics and references", () => {
    let m = scenario1();
    m = moveNodes(m, { "topic:accelerometer.accel_x": { x: 1, y: 1 }, "sensor:accelerometer": { x: 0, y: 0 } });
    const n = removeElement(m, "sensor:accelerometer");
    expect(n.drone.sensors).toEqual([]);
    expect(n.publishers[0].topics).toEqual([]);
    expect(n.subscribers.every((s) => s.topic === "")).toBe(true);
    expect(n.layout?.nodes).toEqual({});
  });

  it("removes a variable but never a sensor's last one", () => {
    const n = removeElement(scenario1(), "topic:accelerometer.accel_y");
    expect(n.drone.sensors[0].variables.map((v) => v.name)).toEqual(["accel_x", "accel_z"]);
    expect(n.publishers[0].topics).not.toContain("usv.accelerometer.accel_y");
    const one = addSensor(emptyModel(), "s").model;
    expect(() => removeElement(one, "topic:s.var_1")).toThrow(/at least one/);
  });

  it("refuses the singletons", () => {
    for (const id of ["drone", "pubBroker", "subBroker", "link"]) expect(() => removeElement(scenario1(), id)).toThrow(EditError);
  });

  it("removes a selection, a sensor together with its own topics", () => {
    const r = removeElements(scenario1(), ["topic:accelerometer.accel_x", "sensor:accelerometer", "sub:sub_1", "drone"]);
    expect(r.model.drone.sensors).toEqual([]);
    expect(r.model.subscribers).toHaveLength(6);
    expect(r.refused).toEqual(["the drone cannot be removed"]);
  });
});

describe("rename", () => {
  it("renames a sensor's topics everywhere, layout included", () => {
    let m = moveNodes(scenario1(), { "topic:accelerometer.accel_x": { x: 3, y: 4 } });
    m = rename(m, "sensor:accelerometer", "imu");
    expect(m.publishers[0].topics).toEqual(["usv.imu.accel_x", "usv.imu.accel_y", "usv.imu.accel_z"]);
    expect(m.subscribers[4].topic).toBe("usv.imu.accel_z");
    expect(m.layout?.nodes?.["topic:imu.accel_x"]).toEqual({ x: 3, y: 4 });
    expect(m.layout?.nodes?.["topic:accelerometer.accel_x"]).toBeUndefined();
  });

  it("renames a variable and the drone", () => {
    let m = rename(scenario1(), "topic:accelerometer.accel_z", "az");
    expect(m.subscribers[6].topic).toBe("usv.accelerometer.az");
    m = rename(m, "drone", "auv");
    expect(m.subscribers[6].topic).toBe("auv.accelerometer.az");
    expect(m.publishers[0].topics[0]).toBe("auv.accelerometer.accel_x");
  });

  it("renames clients and refuses clashes", () => {
    const m = rename(scenario1(), "sub:sub_1", "mean_x");
    expect(m.subscribers[0].name).toBe("mean_x");
    expect(() => rename(m, "sub:sub_2", "pub_1")).toThrow(/already/);
    expect(() => rename(m, "sub:sub_2", "has space")).toThrow(/not a name/);
  });
});

describe("setField", () => {
  it("sets nested fields and removes optional ones", () => {
    let m = setField(scenario1(), "pubBroker", ["endpoint", "port"], 9000);
    expect(m.pubBroker.endpoint.port).toBe(9000);
    m = setField(m, "sub:sub_1", ["endpoint"], undefined);
    expect(m.subscribers[0].endpoint).toBeUndefined();
    m = setField(m, "link", ["pingS"], "0.5");
    expect(m.link).toEqual({ pingS: "0.5" });
    m = setField(m, "link", ["pingS"], undefined);
    expect(m.link).toBeUndefined();
  });

  it("routes names through rename", () => {
    const m = setField(scenario1(), "sensor:accelerometer", ["name"], "imu");
    expect(m.subscribers[0].topic).toBe("usv.imu.accel_x");
  });
});
