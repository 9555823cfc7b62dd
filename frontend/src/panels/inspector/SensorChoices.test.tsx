// @vitest-environment jsdom
import { afterEach, describe, expect, it } from "vitest";
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import InspectorPanel from "./InspectorPanel";
import { EditorContext } from "../../editor/useEditor";
import { createEditorStore } from "../../editor/store";
import { scenario1 } from "../../core/testing/scenario1";
import { currentModel } from "../../core/workbench";

afterEach(cleanup);

describe("a publisher's topics", () => {
  it("takes all of a sensor's topics in one choice", () => {
    const model = scenario1();
    model.publishers[0].topics = ["usv.accelerometer.accel_x"];
    const store = createEditorStore(model, "designer");
    store.dispatch({ type: "select", ids: ["pub:pub_1"] });
    render(<EditorContext.Provider value={store}><InspectorPanel /></EditorContext.Provider>);
    act(() => { fireEvent.click(screen.getByRole("button", { name: "All of accelerometer" })); });
    expect(currentModel(store.getState().wb).publishers[0].topics)
      .toEqual(["usv.accelerometer.accel_x", "usv.accelerometer.accel_y", "usv.accelerometer.accel_z"]);
    expect(screen.queryByRole("button", { name: "All of accelerometer" })).toBeNull(); // all taken: no choice left
  });
});
