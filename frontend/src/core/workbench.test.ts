import { describe, expect, it } from "vitest";
import { currentModel, initialState, reduce, type Action, type WorkbenchState } from "./workbench";
import { emptyModel } from "./templates";
import { scenario1 } from "./testing/scenario1";

const run = (s: WorkbenchState, ...actions: Action[]) => actions.reduce(reduce, s);

describe("workbench reducer", () => {
  it("applies edits allowed to the role and selects what was created", () => {
    const s = run(initialState(emptyModel(), "integrator"), { type: "addSensor" });
    expect(currentModel(s).drone.sensors).toHaveLength(1);
    expect(s.selection).toEqual(["sensor:sensor_1"]);
  });

  it("refuses edits outside the role, leaving the model", () => {
    const s0 = initialState(emptyModel(), "scientist");
    const s = run(s0, { type: "addSensor" });
    expect(currentModel(s)).toBe(currentModel(s0));
    expect(s.notice).toMatch(/scientist view cannot edit sensors/);
    const t = run(initialState(scenario1(), "scientist"), { type: "setField", id: "pub:pub_1", path: ["periodS"], value: "1" });
    expect(t.notice).toMatch(/cannot edit/);
  });

  it("the operator view changes nothing: no undo, redo, copy or delete of saved edits", () => {
    const edited = run(initialState(scenario1(), "scientist"), { type: "remove", ids: ["sub:sub_7"] });
    const op = run(edited, { type: "setRole", role: "operator" });
    const s = run(op, { type: "undo" }, { type: "copy", ids: ["sub:sub_1"] }, { type: "remove", ids: ["sub:sub_1"] });
    expect(currentModel(s)).toBe(currentModel(edited));
    expect(s.clipboard).toBeNull();
    expect(s.notice).toMatch(/operator view cannot edit/);
    expect(currentModel(run(edited, { type: "undo" })).subscribers).toHaveLength(7); // the scientist may undo
  });

  it("lets a scientist connect subscriptions but not publications", () => {
    let s = run(initialState(scenario1(), "scientist"), { type: "connect", source: "topic:accelerometer.accel_z", target: "sub:sub_1" });
    expect(currentModel(s).subscribers[0].topic).toBe("usv.accelerometer.accel_z");
    s = run(s, { type: "disconnect", source: "pub:pub_1", target: "topic:accelerometer.accel_x" });
    expect(s.notice).toMatch(/cannot edit/);
  });

  it("turns model refusals into notices", () => {
    const s = run(initialState(scenario1(), "admin"), { type: "remove", ids: ["drone"] });
    expect(s.notice).toMatch(/cannot be removed/);
    const t = run(initialState(scenario1(), "admin"), { type: "setField", id: "sub:sub_1", path: ["name"], value: "sub_2" });
    expect(t.notice).toMatch(/already/);
  });

  it("undoes and redoes; typing in one field is one step", () => {
    let s = initialState(scenario1(), "scientist");
    for (const v of ["1", "1.", "1.5"]) s = reduce(s, { type: "setField", id: "sub:sub_1", path: ["periodS"], value: v });
    expect(s.history.past).toHaveLength(1);
    s = reduce(s, { type: "undo" });
    expect(currentModel(s).subscribers[0].periodS).toBe("2.0");
    s = reduce(s, { type: "redo" });
    expect(currentModel(s).subscribers[0].periodS).toBe("1.5");
  });

  it("keeps the selection on a renamed element", () => {
    let s = run(initialState(scenario1(), "admin"), { type: "select", ids: ["sub:sub_1"] });
    s = reduce(s, { type: "setField", id: "sub:sub_1", path: ["name"], value: "mean" });
    expect(s.selection).toEqual(["sub:mean"]);
  });

  it("copies and pastes within the role's rights", () => {
    let s = run(initialState(scenario1(), "scientist"), { type: "copy", ids: ["sub:sub_7"] }, { type: "paste" });
    expect(currentModel(s).subscribers.map((x) => x.name)).toContain("sub_7_copy");
    expect(s.selection).toEqual(["sub:sub_7_copy"]);
    s = run(s, { type: "copy", ids: ["pub:pub_1"] }, { type: "paste" });
    expect(s.notice).toMatch(/cannot edit publishers/);
  });

  it("lets any role arrange the diagram; load resets history", () => {
    let s = run(initialState(scenario1(), "operator"), { type: "move", positions: { drone: { x: 10.4, y: 20.6 } } });
    expect(currentModel(s).layout?.nodes?.drone).toEqual({ x: 10, y: 21 });
    s = reduce(s, { type: "load", model: emptyModel() });
    expect(s.history.past).toHaveLength(0);
  });
});

describe("replaceModel", () => {
  it("applies a model whose changes the role owns, refuses others", () => {
    const s0 = initialState(scenario1(), "scientist");
    const next = scenario1();
    next.subscribers[0].periodS = "4.0";
    const s1 = reduce(s0, { type: "replaceModel", model: next });
    expect(currentModel(s1).subscribers[0].periodS).toBe("4.0");
    const bad = scenario1();
    bad.publishers[0].periodS = "0.1";
    const s2 = reduce(s1, { type: "replaceModel", model: bad });
    expect(s2.notice).toBe("the scientist view cannot change the publishers");
    expect(currentModel(s2)).toBe(currentModel(s1));
  });
});

describe("replaceModel with the user's roles (a whole model pasted or dropped)", () => {
  const whole = () => {
    const m = scenario1();
    m.drone.sensors[0].name = "imu";
    m.publishers[0].topics = m.publishers[0].topics.map((t) => t.replace("accelerometer", "imu"));
    m.subscribers.forEach((x) => { x.topic = x.topic.replace("accelerometer", "imu"); });
    return m;
  };

  it("is applied for an admin in any view, and for a user who holds every owner role", () => {
    for (const view of ["designer", "integrator", "scientist", "operator"] as const) {
      const s = reduce(initialState(scenario1(), view), { type: "replaceModel", model: whole(), roles: ["admin"] });
      expect(s.notice).toBeNull();
      expect(currentModel(s).drone.sensors[0].name).toBe("imu");
    }
    const s = reduce(initialState(scenario1(), "scientist"), { type: "replaceModel", model: whole(), roles: ["designer", "integrator", "scientist"] });
    expect(currentModel(s).drone.sensors[0].name).toBe("imu");
  });

  it("is refused for a scientist with the parts in words, their owners and the ways out", () => {
    const s0 = initialState(scenario1(), "scientist");
    const s = reduce(s0, { type: "replaceModel", model: whole(), roles: ["scientist"] });
    expect(currentModel(s)).toBe(currentModel(s0));
    expect(s.notice).toBe("This model changes the sensors and the publishers, which your roles (scientist) may not change. "
      + "Ask a user with the designer or integrator role (or an admin) to apply it, or import it as a new project from the Projects page.");
    expect(s.notice).not.toMatch(/\/drone|\/publishers/);
  });
});

describe("the save rule applied at edit time", () => {
  it("refuses an integrator rename that would rewrite others' references", () => {
    const s = reduce(initialState(scenario1(), "integrator"), { type: "setField", id: "sensor:accelerometer", path: ["name"], value: "imu" });
    expect(s.notice).toBe("this edit changes the publishers, the subscriptions, which the integrator view may not change");
    expect(currentModel(s).drone.sensors[0].name).toBe("accelerometer");
  });

  it("lets an integrator rename an unreferenced sensor", () => {
    let s = initialState(scenario1(), "integrator");
    s = reduce(s, { type: "addSensor" });
    s = reduce(s, { type: "setField", id: "sensor:sensor_1", path: ["name"], value: "ctd" });
    expect(s.notice).toBeNull();
    expect(currentModel(s).drone.sensors.map((x) => x.name)).toEqual(["accelerometer", "ctd"]);
  });
});
