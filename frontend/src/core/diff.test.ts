import { describe, expect, it } from "vitest";
import { diffModels } from "./diff";
import { scenario1 } from "./testing/scenario1";
import { moveNodes, rename } from "./ops";

describe("diffModels", () => {
  it("is empty for equal models and ignores the layout", () => {
    expect(diffModels(scenario1(), moveNodes(scenario1(), { drone: { x: 1, y: 1 } }))).toEqual([]);
  });

  it("names changed fields by element name", () => {
    const b = scenario1();
    b.subscribers[0].periodS = "1.0";
    b.subscribers.reverse();
    expect(diffModels(scenario1(), b)).toEqual([
      { op: "replace", pointer: "/subscribers/sub_1/periodS", before: "2.0", after: "1.0" },
    ]);
  });

  it("shows a rename as remove and add", () => {
    const d = diffModels(scenario1(), rename(scenario1(), "sub:sub_7", "z_max"));
    expect(d.map((c) => `${c.op} ${c.pointer}`)).toEqual(["remove /subscribers/sub_7", "add /subscribers/z_max"]);
  });
});
