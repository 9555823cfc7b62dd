import { describe, expect, it } from "vitest";
import { byElement, erroneousElements, localDiagnostics, placeDiagnostics } from "./diagnostics";
import { MODD_SCHEMA } from "./schema";
import { scenario1 } from "./testing/scenario1";
import { addPublisher, addSubscriber } from "./ops";

describe("diagnostics", () => {
  it("finds nothing wrong with scenario 1", () => {
    expect(localDiagnostics(scenario1(), MODD_SCHEMA)).toEqual([]);
  });

  it("flags an unconnected subscriber and a publisher without topics, on their fields", () => {
    let m = addSubscriber(scenario1()).model;
    m = addPublisher(m).model;
    m.subscribers[0].periodS = "two";
    const placed = placeDiagnostics(m, localDiagnostics(m, MODD_SCHEMA));
    const where = placed.map((d) => `${d.elementId}#${d.field.join(".")}`);
    expect(where).toEqual(expect.arrayContaining(["sub:sub_8#topic", "pub:pub_2#topics", "sub:sub_1#periodS"]));
    expect(erroneousElements(placed)).toEqual(new Set(["sub:sub_8", "pub:pub_2", "sub:sub_1"]));
  });

  it("warns when a subscribed topic has no publisher", () => {
    const m = scenario1();
    m.publishers[0].topics = ["usv.accelerometer.accel_x", "usv.accelerometer.accel_y"];
    const d = localDiagnostics(m, MODD_SCHEMA);
    expect(d.filter((x) => x.severity === "warning").map((x) => x.pointer)).toEqual(["/subscribers/4/topic", "/subscribers/5/topic", "/subscribers/6/topic"]);
  });

  it("places backend diagnostics by pointer, errors first", () => {
    const placed = placeDiagnostics(scenario1(), [
      { severity: "warning", message: "w", pointer: "/subscribers/0" },
      { severity: "error", message: "e", pointer: "/subscribers/0/periodS", line: 3, col: 5 },
      { severity: "error", message: "no pointer" },
    ]);
    const map = byElement(placed);
    expect(map.get("sub:sub_1")?.map((d) => d.message)).toEqual(["e", "w"]);
    expect(map.get("drone")?.[0].message).toBe("no pointer");
  });
});
