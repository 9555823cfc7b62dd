import { describe, expect, it } from "vitest";
import { createEditorStore, isDirty } from "./store";
import { scenario1 } from "../core/testing/scenario1";

describe("isDirty", () => {
  it("is false again when values are set back by hand to the saved ones", () => {
    const store = createEditorStore(scenario1(), "scientist");
    expect(isDirty(store.getState())).toBe(false);
    store.dispatch({ type: "setField", id: "sub:sub_1", path: ["periodS"], value: "4.0" });
    expect(isDirty(store.getState())).toBe(true);
    store.dispatch({ type: "setField", id: "sub:sub_1", path: ["periodS"], value: "2.0" });
    expect(isDirty(store.getState())).toBe(false); // no edit left to save
    store.dispatch({ type: "setField", id: "sub:sub_1", path: ["periodS"], value: "2" });
    expect(isDirty(store.getState())).toBe(false); // the same number, spelled otherwise
    store.dispatch({ type: "setField", id: "sub:sub_1", path: ["aggregation"], value: "MAX" });
    expect(isDirty(store.getState())).toBe(true);
  });
});
