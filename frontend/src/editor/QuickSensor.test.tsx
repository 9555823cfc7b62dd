// @vitest-environment jsdom
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import { afterEach, describe, expect, it } from "vitest";
import { createEditorStore } from "./store";
import { EditorContext } from "./useEditor";
import { QuickSensor } from "./QuickSensor";
import { currentModel } from "../core/workbench";
import { emptyModel } from "../core/templates";
import { canUndo } from "../core/history";

afterEach(cleanup);

describe("QuickSensor", () => {
  it("adds a sensor with all its variables and units in one edit", () => {
    const store = createEditorStore(emptyModel(), "integrator");
    render(<EditorContext.Provider value={store}><QuickSensor /></EditorContext.Provider>);
    fireEvent.change(screen.getByLabelText("Sensor name"), { target: { value: "accelerometer" } });
    fireEvent.change(screen.getByLabelText("Variables"), { target: { value: "accel_x, accel_y, accel_z" } });
    fireEvent.change(screen.getByLabelText("Unit"), { target: { value: "METER_PER_SECOND_SQUARED" } });
    act(() => { fireEvent.click(screen.getByRole("button", { name: "Add sensor (3 variables)" })); });
    const sensors = currentModel(store.getState().wb).drone.sensors;
    expect(sensors.map((s) => s.name)).toEqual(["accelerometer"]);
    expect(sensors[0].variables).toEqual(["x", "y", "z"].map((a) => ({ name: `accel_${a}`, unit: "METER_PER_SECOND_SQUARED" })));
    act(() => store.dispatch({ type: "undo" })); // one undo step takes it all back
    expect(currentModel(store.getState().wb).drone.sensors).toEqual([]);
    expect(canUndo(store.getState().wb.history)).toBe(false);
  });

  it("names a taken sensor name instead of adding it", () => {
    const store = createEditorStore(emptyModel(), "integrator");
    render(<EditorContext.Provider value={store}><QuickSensor /></EditorContext.Provider>);
    for (let i = 0; i < 2; i++) {
      fireEvent.change(screen.getByLabelText("Sensor name"), { target: { value: "ctd" } });
      fireEvent.change(screen.getByLabelText("Variables"), { target: { value: "temp" } });
      act(() => { fireEvent.click(screen.getByRole("button", { name: "Add sensor" })); });
    }
    expect(screen.getByRole("alert").textContent).toMatch(/exists already/);
    expect(currentModel(store.getState().wb).drone.sensors).toHaveLength(1);
  });
});
