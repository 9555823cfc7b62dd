// @vitest-environment jsdom
/**
 * The Inspector's campaign form: edits made by a person (typing, choosing,
 * buttons) produce the expected model, which the project's own validator
 * (modd_model, Python, run from the project's .venv) accepts; the located
 * errors that validator and the live plan's channel check give are shown at
 * the field they name; model strings are text, never markup.
 */
import { execFileSync } from "node:child_process";
import { existsSync } from "node:fs";
import { resolve } from "node:path";
import { afterEach, beforeAll, describe, expect, it } from "vitest";
import { act, cleanup, fireEvent, render, screen, within } from "@testing-library/react";
import InspectorPanel from "./InspectorPanel";
import { EditorContext } from "../../editor/useEditor";
import { createEditorStore, type EditorStore } from "../../editor/store";
import { scenario1 } from "../../core/testing/scenario1";
import { currentModel } from "../../core/workbench";
import { planKey } from "../../core/planKey";
import type { ModdModel } from "../../core/model.gen";
import type { Diagnostic } from "../../core/diagnostics";
import type { Role } from "../../core/roles";
import { sameMeaning } from "../../core/canonical";

const repo = resolve(__dirname, "../../../..");
const python = resolve(repo, ".venv/bin/python");
/** Time for a test that runs the project's Python (a loaded machine; as roundTrip.test.ts). */
const PYTHON_MS = 60_000;

/** modd_model's validation of each model, and (with `plan`) the live plan's channel check, as the backend runs them. */
function validated(models: ModdModel[], plan = false): Diagnostic[][] {
  const script = `
import json, sys
from modd_model import validate
from modd_plan.campaign import channel_diagnostics
out = []
for m in json.load(sys.stdin):
    found = validate(m) + (channel_diagnostics(m) if ${plan ? "True" : "False"} else [])
    out.append([{"severity": d.severity, "message": d.message, "pointer": d.pointer} for d in found])
print(json.dumps(out))`;
  return JSON.parse(execFileSync(python, ["-c", script], { cwd: repo, input: JSON.stringify(models) }).toString()) as Diagnostic[][];
}

/** Each model printed as .modd text and parsed back by modd_model (what the Text panel shows and applies). */
function viaText(models: ModdModel[]): unknown[] {
  const script = `
import json, sys
from modd_model import dumps, load_text
print(json.dumps([load_text(dumps(m, "modd"), "m.modd").model for m in json.load(sys.stdin)]))`;
  return JSON.parse(execFileSync(python, ["-c", script], { cwd: repo, input: JSON.stringify(models) }).toString()) as unknown[];
}

const errorsOf = (diags: Diagnostic[]) => diags.filter((d) => d.severity === "error");

/** Scenario 1 with an NMEA GPS read on a serial device (a device a vehicle may replace). */
function withDevice(): ModdModel {
  const m = scenario1();
  m.drone.sensors.push({ name: "gps", kind: "nmea", device: { path: "/dev/ttyUSB0" }, variables: [{ name: "lat", unit: "NONE", nmea: { sentence: "GGA", field: "lat" } }] });
  m.publishers[0].topics.push("usv.gps.lat");
  return m;
}

function mount(role: Role, model: ModdModel = scenario1()): EditorStore {
  const store = createEditorStore(model, role);
  render(<EditorContext.Provider value={store}><InspectorPanel /></EditorContext.Provider>);
  return store;
}

const model = (store: EditorStore) => currentModel(store.getState().wb);
const part = (name: string) => within(screen.getByRole("group", { name }));
function type(input: HTMLElement, text: string) {
  fireEvent.focus(input);
  fireEvent.change(input, { target: { value: text } });
  fireEvent.blur(input);
}
const click = (name: string | RegExp) => fireEvent.click(screen.getByRole("button", { name }));
/** The field (data-field) of a part whose label starts with `label`. */
const field = (name: string, label: RegExp) => part(name).getByLabelText(label).closest(".field") as HTMLElement;

/** The backend's answer (validation, channel sums) for the model shown, as the live plan gives it. */
function answer(store: EditorStore, diagnostics: Diagnostic[]) {
  act(() => store.patch({ plan: { busy: false, error: null, result: { ok: false, plan: null, diagnostics, elapsed_ms: 1 }, modelKey: planKey(model(store)) } }));
}

beforeAll(() => {
  if (!existsSync(python)) throw new Error(`${python} is missing: run scripts/setup.sh`);
});
afterEach(cleanup);

describe("CampaignForm", () => {
  it("makes a one-drone model a campaign, edits vehicles and channels, and the validator accepts each step", () => {
    const store = mount("designer", withDevice());
    const steps: ModdModel[] = [];
    click("Make it a campaign");
    steps.push(model(store));
    expect(model(store).campaign).toEqual({
      name: "usv_campaign",
      vehicles: [{ name: "usv_1" }, { name: "usv_2", pubBroker: { endpoint: { host: "127.0.0.1", port: 7172 } } }],
    });
    click("Add vehicle");
    type(part("Vehicle usv_1").getByLabelText(/^name/), "north");
    click("Add channel");
    type(part("Channel ch_1").getByLabelText(/^rate bps/), "20000");
    type(part("Channel ch_1").getByLabelText(/^duty cycle/), "0.1");
    type(part("Channel ch_1").getByLabelText(/^name/), "lake");
    fireEvent.change(part("Vehicle north").getByLabelText(/^channel/), { target: { value: "lake" } });
    fireEvent.change(part("Vehicle usv_2").getByLabelText(/^channel/), { target: { value: "lake" } });
    steps.push(model(store));
    type(part("Vehicle usv_3").getByLabelText(/^sub broker endpoint host/), "boat.example");
    type(part("Vehicle usv_3").getByLabelText(/^sub broker endpoint port/), "7300");
    type(part("Vehicle usv_3").getByLabelText(/^device of gps/), "/dev/ttyUSB3");
    fireEvent.change(part("Vehicle usv_3").getByLabelText(/^link transport/), { target: { value: "udp" } });
    type(part("Vehicle usv_3").getByLabelText(/^description/), "East boat");
    steps.push(model(store));
    expect(model(store).campaign).toEqual({
      name: "usv_campaign",
      channels: [{ name: "lake", rateBps: 20000, dutyCycle: "0.1" }],
      vehicles: [
        { name: "north", channel: "lake" },
        { name: "usv_2", channel: "lake", pubBroker: { endpoint: { host: "127.0.0.1", port: 7172 } } },
        {
          name: "usv_3", description: "East boat", pubBroker: { endpoint: { host: "127.0.0.1", port: 7173 } },
          subBroker: { endpoint: { host: "boat.example", port: 7300 } }, devices: [{ sensor: "gps", path: "/dev/ttyUSB3" }],
          link: { transport: "udp" },
        },
      ],
    });
    // A device cleared is the mission's again; a channel removed leaves its vehicles.
    type(part("Vehicle usv_3").getByLabelText(/^device of gps/), "");
    fireEvent.click(part("Channel lake").getByRole("button", { name: "Remove Channel lake" }));
    fireEvent.click(part("Vehicle usv_2").getByRole("button", { name: "Remove Vehicle usv_2" }));
    steps.push(model(store));
    expect(model(store).campaign?.vehicles).toEqual([
      { name: "north" },
      { name: "usv_3", description: "East boat", pubBroker: { endpoint: { host: "127.0.0.1", port: 7173 } },
        subBroker: { endpoint: { host: "boat.example", port: 7300 } }, link: { transport: "udp" } },
    ]);
    expect(model(store).campaign?.channels).toBeUndefined();
    expect(validated(steps).map(errorsOf)).toEqual([[], [], [], []]);
    // and each is written in the Text panel's .modd and read back unchanged
    viaText(steps).forEach((back, i) => expect(sameMeaning(back, { ...steps[i], layout: undefined })).toBe(true));
    click("Back to one drone");
    expect(model(store).campaign).toBeUndefined();
    act(() => store.dispatch({ type: "undo" })); // the model's own undo: the campaign is back
    expect(model(store).campaign?.vehicles.map((v) => v.name)).toEqual(["north", "usv_3"]);
  }, PYTHON_MS);

  it("shows the validator's and the live plan's located errors at the field they name", () => {
    const store = mount("designer", withDevice());
    click("Make it a campaign");
    click("Add channel");
    type(part("Channel ch_1").getByLabelText(/^rate bps/), "10");
    fireEvent.change(part("Vehicle usv_1").getByLabelText(/^channel/), { target: { value: "ch_1" } });
    fireEvent.change(part("Vehicle usv_2").getByLabelText(/^channel/), { target: { value: "ch_1" } });
    const overloaded = model(store);
    const [planned] = validated([overloaded], true);
    // the mission is valid: the channel's sum is the one problem (the backend pins it as a warning)
    expect(errorsOf(planned).map((d) => d.pointer)).toEqual(["/campaign/channels/0"]);
    answer(store, planned);
    expect(part("Channel ch_1").getByText(/over its rate of 10 B\/s/)).toBeTruthy();
    // Two vehicles on one PubBroker, a channel nobody declares, a bad port, a device of no sensor:
    type(part("Vehicle usv_2").getByLabelText(/^pub broker endpoint port/), "7171");
    type(part("Vehicle usv_2").getByLabelText(/^sub broker endpoint port/), "70000");
    act(() => store.dispatch({ type: "editCampaign", edit: { op: "set", path: ["vehicles", "0", "channel"], value: "radio9" } }));
    const [found] = validated([model(store)]);
    const pointers = errorsOf(found).map((d) => d.pointer);
    expect(pointers).toEqual(expect.arrayContaining(["/campaign/vehicles/0/channel", "/campaign/vehicles/1/subBroker/endpoint/port"]));
    answer(store, found);
    expect(within(field("Vehicle usv_1", /^channel/)).getByText(/no channel 'radio9' in the campaign \(ch_1\)/)).toBeTruthy();
    expect(within(field("Vehicle usv_2", /^sub broker endpoint port/)).getAllByRole("alert").length).toBeGreaterThan(0);
    const shared = part("Vehicle usv_2").getByText(/one PubBroker endpoint 127\.0\.0\.1:7171/);
    expect(shared.closest("details")?.querySelector("summary")?.textContent).toBe("PubBroker"); // at the vehicle's PubBroker
    expect(within(field("Vehicle usv_1", /^name/)).queryByRole("alert")).toBeNull();
  }, PYTHON_MS);

  it("shows hostile strings as text, and is read-only outside the designer's view", () => {
    const m = scenario1();
    const hostile = `<img src=x onerror="alert(1)">&amp; \u202e`;
    m.campaign = { name: "lake", description: hostile, vehicles: [{ name: "v1", description: hostile }] };
    mount("scientist", m);
    expect(document.querySelector(".campaign-form img")).toBeNull();
    expect((part("Vehicle v1").getByLabelText(/^description/) as HTMLInputElement).value).toBe(hostile);
    expect(screen.getByText(/Read-only in the scientist view/)).toBeTruthy();
    expect(screen.queryByRole("button", { name: "Add vehicle" })).toBeNull();
    expect((part("Vehicle v1").getByLabelText(/^name/) as HTMLInputElement).readOnly).toBe(true);
  });

  it("offers the campaign with the platform selected too, and refuses it in a view that may not edit it", () => {
    const store = mount("designer");
    act(() => store.dispatch({ type: "select", ids: ["drone"] }));
    expect(screen.getByRole("button", { name: "Make it a campaign" })).toBeTruthy();
    act(() => store.dispatch({ type: "setRole", role: "integrator" }));
    act(() => store.dispatch({ type: "editCampaign", edit: { op: "start" } }));
    expect(model(store).campaign).toBeUndefined();
    expect(store.getState().wb.notice).toMatch(/cannot edit the campaign/);
  });
});
