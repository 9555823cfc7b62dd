// @vitest-environment jsdom
import { afterEach, describe, expect, it } from "vitest";
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import InspectorPanel from "./InspectorPanel";
import { EditorContext } from "../../editor/useEditor";
import { createEditorStore, type EditorStore } from "../../editor/store";
import { scenario1 } from "../../core/testing/scenario1";
import { currentModel } from "../../core/workbench";
import type { Role } from "../../core/roles";

function mount(role: Role, selection: string[]): EditorStore {
  const store = createEditorStore(scenario1(), role);
  store.dispatch({ type: "select", ids: selection });
  render(<EditorContext.Provider value={store}><InspectorPanel /></EditorContext.Provider>);
  return store;
}

afterEach(cleanup);

describe("InspectorPanel", () => {
  it("renders the schema's fields and help for a subscriber", () => {
    mount("scientist", ["sub:sub_1"]);
    expect(screen.getByRole("heading", { name: "Subscriber sub_1" })).toBeTruthy();
    expect(screen.getByText(/A consumer on the base station/)).toBeTruthy();
    expect((screen.getByLabelText(/^aggregation/) as HTMLSelectElement).value).toBe("AVERAGE");
    expect((screen.getByLabelText(/^topic/) as HTMLSelectElement).value).toBe("usv.accelerometer.accel_x");
    expect(screen.getByText("How the samples of each period are reduced.")).toBeTruthy();
  });

  it("shows the MAVLink field mapping only for a variable of a MAVLink sensor", () => {
    const store = mount("integrator", ["topic:accelerometer.accel_x"]);
    expect(screen.queryByLabelText(/^message/)).toBeNull();
    expect(document.querySelector('[data-field^="source"]')).toBeNull();
    act(() => store.dispatch({ type: "setField", id: "sensor:accelerometer", path: ["kind"], value: "mavlink" }));
    expect(document.querySelector('[data-field^="source"]')).not.toBeNull();
  });

  it("edits an NMEA sensor as a form: its device, then each variable's sentence field", () => {
    const store = mount("integrator", ["sensor:accelerometer"]);
    expect(document.querySelector('[data-field^="device"]')).toBeNull();
    act(() => store.dispatch({ type: "setField", id: "sensor:accelerometer", path: ["kind"], value: "nmea" }));
    expect(document.querySelector('[data-field="device.baud"]')).not.toBeNull();
    expect(document.querySelector('[data-field^="line"]')).toBeNull();
    act(() => store.dispatch({ type: "setField", id: "sensor:accelerometer", path: ["device", "path"], value: "/dev/ttyUSB0" }));
    act(() => store.dispatch({ type: "select", ids: ["topic:accelerometer.accel_x"] }));
    expect(document.querySelector('[data-field^="source"]')).toBeNull();
    expect(document.querySelector('[data-field^="modbus"]')).toBeNull();
    const sentence = screen.getByLabelText(/^nmea sentence/) as HTMLSelectElement;
    expect([...sentence.options].map((o) => o.value)).toContain("GGA");
    act(() => store.dispatch({ type: "setField", id: "topic:accelerometer.accel_x", path: ["nmea", "sentence"], value: "DPT" }));
    act(() => store.dispatch({ type: "setField", id: "topic:accelerometer.accel_x", path: ["nmea", "field"], value: "depth" }));
    const sensor = currentModel(store.getState().wb).drone.sensors[0];
    expect(sensor.device?.path).toBe("/dev/ttyUSB0");
    expect(sensor.variables[0].nmea).toEqual({ sentence: "DPT", field: "depth" });
  });

  it("edits a source's condition (where) as a form: MWV true wind only", () => {
    const store = mount("integrator", ["sensor:accelerometer"]);
    const nmeaOnly = () => ["checksum", "fix"].map((f) => document.querySelector(`[data-field="${f}"]`) !== null);
    expect(nmeaOnly()).toEqual([false, false]);
    act(() => store.dispatch({ type: "setField", id: "sensor:accelerometer", path: ["kind"], value: "nmea" }));
    expect(nmeaOnly()).toEqual([true, true]);
    act(() => store.dispatch({ type: "select", ids: ["topic:accelerometer.accel_x"] }));
    expect(document.querySelector('[data-field="nmea.where.field"]')).not.toBeNull();
    const op = screen.getByLabelText(/^nmea where op/) as HTMLSelectElement;
    expect([...op.options].map((o) => o.value)).toEqual(["", "=", "!=", "<", "<=", ">", ">="]);
    expect(op.value).toBe("=");
    const id = "topic:accelerometer.accel_x";
    act(() => store.dispatch({ type: "setField", id, path: ["nmea", "sentence"], value: "MWV" }));
    act(() => store.dispatch({ type: "setField", id, path: ["nmea", "field"], value: "angle" }));
    act(() => store.dispatch({ type: "setField", id, path: ["nmea", "where", "field"], value: "reference" }));
    act(() => store.dispatch({ type: "setField", id, path: ["nmea", "where", "value"], value: "T" }));
    fireEvent.change(screen.getByLabelText(/^nmea where op/), { target: { value: "!=" } });
    const variable = () => currentModel(store.getState().wb).drone.sensors[0].variables[0];
    expect(variable().nmea).toEqual({ sentence: "MWV", field: "angle", where: { field: "reference", value: "T", op: "!=" } });
    for (const part of ["field", "value", "op"]) {
      act(() => store.dispatch({ type: "setField", id, path: ["nmea", "where", part], value: undefined }));
    }
    expect(variable().nmea).toEqual({ sentence: "MWV", field: "angle" }); // no empty condition left
  });

  it("shows an ascii variable's condition on a column or a key", () => {
    const store = mount("integrator", ["sensor:accelerometer"]);
    act(() => store.dispatch({ type: "setField", id: "sensor:accelerometer", path: ["kind"], value: "ascii" }));
    act(() => store.dispatch({ type: "select", ids: ["topic:accelerometer.accel_x"] }));
    const fields = [...document.querySelectorAll("[data-field^='ascii.where']")].map((e) => e.getAttribute("data-field"));
    expect(fields).toEqual(["ascii.where.column", "ascii.where.key", "ascii.where.op", "ascii.where.value"]);
  });

  it("commits text fields on Enter, as one undoable edit", () => {
    const store = mount("scientist", ["sub:sub_1"]);
    const period = screen.getByLabelText(/^period/) as HTMLInputElement;
    fireEvent.change(period, { target: { value: "4.0" } });
    expect(currentModel(store.getState().wb).subscribers[0].periodS).toBe("2.0");
    act(() => { fireEvent.keyDown(period, { key: "Enter" }); });
    expect(currentModel(store.getState().wb).subscribers[0].periodS).toBe("4.0");
    act(() => store.dispatch({ type: "undo" }));
    expect(currentModel(store.getState().wb).subscribers[0].periodS).toBe("2.0");
  });

  it("shows a field's error under it", () => {
    const store = mount("scientist", ["sub:sub_1"]);
    act(() => store.dispatch({ type: "setField", id: "sub:sub_1", path: ["periodS"], value: "two" }));
    expect(screen.getByRole("alert").textContent).toMatch(/period \(s\): a decimal number/);
    expect(screen.getByLabelText(/^period/).getAttribute("aria-invalid")).toBe("true");
  });

  it("is read-only outside the role", () => {
    mount("scientist", ["pub:pub_1"]);
    expect(screen.getByRole("note").textContent).toMatch(/Read-only in the scientist view/);
    expect((screen.getByLabelText(/^period/) as HTMLInputElement).readOnly).toBe(true);
  });

  it("lists problems when nothing is selected", () => {
    const store = mount("scientist", []);
    act(() => store.dispatch({ type: "addSubscriber" }));
    act(() => store.dispatch({ type: "select", ids: [] }));
    expect(screen.getByText(/1 problem/)).toBeTruthy();
    expect(screen.getByRole("button", { name: "sub:sub_8" })).toBeTruthy();
  });
  it("shows a publisher → topic edge in the model's words and deletes it for its owner", () => {
    const store = mount("designer", ["publishes:pub:pub_1->topic:accelerometer.accel_x"]);
    expect(screen.getByRole("heading", { name: "Publisher → topic" })).toBeTruthy();
    expect(screen.getByRole("button", { name: "usv.accelerometer.accel_x" })).toBeTruthy();
    fireEvent.click(screen.getByRole("button", { name: "Delete this edge" }));
    const pub = currentModel(store.getState().wb).publishers.find((p) => p.name === "pub_1");
    expect(pub?.topics).not.toContain("usv.accelerometer.accel_x");
  });

  it("keeps a topic → subscriber edge read-only for a role that does not own subscribers", () => {
    mount("designer", ["subscribes:topic:accelerometer.accel_x->sub:sub_1"]);
    expect(screen.getByText(/subscribes to/)).toBeTruthy();
    expect(screen.queryByRole("button", { name: "Delete this edge" })).toBeNull();
    expect(screen.getByRole("note").textContent).toMatch(/Read-only in the designer view/);
  });

  it("opens the link's radio settings as a form for the designer", () => {
    const store = mount("designer", ["link"]);
    expect(screen.getByRole("heading", { name: /^Link/ })).toBeTruthy();
    const fields = [...document.querySelectorAll("[data-field]")].map((e) => e.getAttribute("data-field"));
    expect(fields.some((f) => f?.startsWith("radio"))).toBe(true);
    expect(fields).toContain("transport");
    const transport = screen.getByLabelText(/^transport/) as HTMLSelectElement;
    fireEvent.change(transport, { target: { value: "udp" } });
    expect(currentModel(store.getState().wb).link?.transport).toBe("udp");
  });
});
