// @vitest-environment jsdom
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import { afterEach, describe, expect, it } from "vitest";
import { createEditorStore } from "./store";
import { EditorContext } from "./useEditor";
import { QuickSubscribe } from "./QuickSubscribe";
import { currentModel } from "../core/workbench";
import { scenario1 } from "../core/testing/scenario1";

afterEach(cleanup);

function pick(select: HTMLElement, values: string[]) {
  for (const o of (select as HTMLSelectElement).options) o.selected = values.includes(o.value);
  fireEvent.change(select);
}

function mount() {
  const store = createEditorStore(scenario1(), "scientist");
  render(<EditorContext.Provider value={store}><QuickSubscribe /></EditorContext.Provider>);
  return store;
}

describe("QuickSubscribe", () => {
  it("spells the chosen topic out in full under the narrow form", () => {
    mount();
    expect(screen.getByRole("status", { name: "Subscriptions to make" }).textContent)
      .toBe("usv.accelerometer.accel_x (m/s²) AVERAGE every 1.0 s");
  });

  it("lists each topic under its sensor by its variable and unit, the full name as its tooltip", () => {
    mount();
    const select = screen.getByLabelText("Topic") as HTMLSelectElement;
    const accel = [...select.querySelectorAll("optgroup")].find((g) => g.label === "accelerometer");
    expect([...(accel?.querySelectorAll("option") ?? [])].map((o) => [o.textContent, o.title])).toEqual(
      ["accel_x", "accel_y", "accel_z"].map((v) => [`${v} (m/s²)`, `usv.accelerometer.${v} (m/s²)`]));
  });

  it("makes every topic × period × aggregation in one submit", () => {
    const store = mount();
    const before = currentModel(store.getState().wb).subscribers.length;
    pick(screen.getByLabelText("Topic"), ["usv.accelerometer.accel_y", "usv.accelerometer.accel_z"]);
    fireEvent.change(screen.getByLabelText("Every (s)"), { target: { value: "0.25, 2" } });
    pick(screen.getByLabelText("Aggregation"), ["MIN", "MAX"]);
    expect(screen.getByRole("status", { name: "Subscriptions to make" }).textContent).toMatch(/^8 subscriptions: usv\.accelerometer\.accel_y \(m\/s²\) MIN every 0\.25 s;/);
    act(() => { fireEvent.click(screen.getByRole("button", { name: "Subscribe (8)" })); });
    const subs = currentModel(store.getState().wb).subscribers.slice(before);
    const made = subs.map((s) => `${s.topic} ${s.periodS} ${s.aggregation}`).sort();
    const expected = ["accel_y", "accel_z"].flatMap((v) => ["0.25", "2.0"].flatMap((p) => ["MIN", "MAX"].map((a) => `usv.accelerometer.${v} ${p} ${a}`))).sort();
    expect(made).toEqual(expected);
  });

  it("refuses what is not a period, naming it", () => {
    mount();
    fireEvent.change(screen.getByLabelText("Every (s)"), { target: { value: "2, fast" } });
    expect(screen.getByRole("alert").textContent).toBe("Not a period: fast");
    expect((screen.getByRole("button", { name: /Subscribe/ }) as HTMLButtonElement).disabled).toBe(true);
  });
  it("lists every aggregation and toggles one with a plain click, no modifier key", () => {
    mount();
    const select = screen.getByLabelText("Aggregation") as HTMLSelectElement;
    expect(select.size).toBe(select.options.length); // none hidden below the fold
    expect([...select.options].map((o) => o.value)).toEqual(expect.arrayContaining(["LAST", "FIRST", "ALL"]));
    const option = (v: string) => [...select.options].find((o) => o.value === v)!;
    fireEvent.mouseDown(option("MAX"));
    expect([...select.selectedOptions].map((o) => o.value).sort()).toEqual(["AVERAGE", "MAX"]);
    fireEvent.mouseDown(option("AVERAGE"));
    expect([...select.selectedOptions].map((o) => o.value)).toEqual(["MAX"]);
    fireEvent.mouseDown(option("MAX")); // the last one stays
    expect([...select.selectedOptions].map((o) => o.value)).toEqual(["MAX"]);
  });

  it("leaves the last subscription made selected, so that Duplicate makes it twice", () => {
    const store = mount();
    const before = currentModel(store.getState().wb).subscribers.length;
    act(() => { fireEvent.click(screen.getByRole("button", { name: "Subscribe" })); });
    const made = currentModel(store.getState().wb).subscribers.slice(before);
    expect(store.getState().wb.selection).toEqual([`sub:${made[made.length - 1].name}`]);
    act(() => { store.dispatch({ type: "duplicate", ids: store.getState().wb.selection }); });
    const after = currentModel(store.getState().wb).subscribers.slice(before);
    expect(after).toHaveLength(2);
    expect(after.map((x) => `${x.topic} ${x.periodS} ${x.aggregation}`)).toEqual([1, 2].map(() => "usv.accelerometer.accel_x 1.0 AVERAGE"));
  });
});
