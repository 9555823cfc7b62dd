// @vitest-environment jsdom
import { afterEach, describe, expect, it } from "vitest";
import { act, cleanup, fireEvent, render, screen, waitFor } from "@testing-library/react";
import PlanPanel from "./PlanPanel";
import { EditorContext } from "../../editor/useEditor";
import { createEditorStore } from "../../editor/store";
import { ServicesContext, type Services } from "../../app/services";
import { useLivePlan } from "../../app/useLivePlan";
import { scenario1 } from "../../core/testing/scenario1";
import planJson from "../../core/testing/scenario1.plan.json";
import type { PlanJson } from "../../core/plan";
import type { ArchiveFile, PlanResult } from "../../api/types";

afterEach(cleanup);

const radio: NonNullable<PlanJson["radio"]> = {
  kind: "lora", bytes_per_s: 3.8, packets_per_hour: 450, air_time_s_per_hour: 25.46, duty_cycle: 0.01,
  duty_share: 0.77, figures: "estimate", air_time_bound_s_per_hour: 27.76, energy_j_per_hour: 26.4,
  battery_wh: null, battery_share_per_hour: null, costs: [], error: null, diagnostics: [], proposals: [],
};

/** The live plan with a fake backend: the archives it holds, and every plan request's `calibrate`. */
function mount(archives: string[]) {
  const asked: Array<string | undefined> = [];
  const api = {
    listArchives: async () => archives.map((name) => ({ name }) as ArchiveFile),
    plan: async (_input: unknown, _signal?: AbortSignal, calibrate?: string): Promise<PlanResult> => {
      asked.push(calibrate);
      const calibrated = calibrate
        ? { calibrated_from: calibrate.split("/")[1], calibration: { windows_limit: 2000, streams: [], not_calibrated: ["usv.accelerometer.accel_y/AVERAGE/8.0"] } }
        : {};
      const plan: PlanJson = { ...(planJson as unknown as PlanJson), radio: { ...radio, ...calibrated } };
      return { ok: true, plan, diagnostics: [], elapsed_ms: 3 };
    },
  } as unknown as Services["api"];
  const store = createEditorStore(scenario1(), "designer");
  function Live() { useLivePlan(0); return <PlanPanel />; }
  render(
    <ServicesContext.Provider value={{ api, openStream: () => { throw new Error("no stream"); } }}>
      <EditorContext.Provider value={store}><Live /></EditorContext.Provider>
    </ServicesContext.Provider>,
  );
  return { store, asked };
}

describe("Calibration (the Plan panel's archive picker)", () => {
  it("re-plans calibrated by the chosen archive and says so", async () => {
    const { store, asked } = mount(["run-0000.mcap", "run-0001.mcap"]);
    const picker = await screen.findByRole("combobox", { name: "Calibrate by archive" });
    expect(asked).toEqual([undefined]);
    expect(screen.queryByTestId("calibrated-from")).toBeNull();
    // the archives are listed asynchronously: a choice before its option exists is no choice
    await waitFor(() => expect(Array.from(picker.querySelectorAll("option"), (o) => o.value)).toContain("usv/run-0001.mcap"));
    act(() => { fireEvent.change(picker, { target: { value: "usv/run-0001.mcap" } }); });
    expect(store.getState().plan.calibrate).toBe("usv/run-0001.mcap");
    await waitFor(() => expect(asked).toEqual([undefined, "usv/run-0001.mcap"]));
    const said = await screen.findByTestId("calibrated-from");
    expect(said.textContent).toMatch(/sized from run-0001.mcap .*not in it: usv.accelerometer.accel_y\/AVERAGE\/8.0/);
    act(() => { fireEvent.change(picker, { target: { value: "" } }); });
    await waitFor(() => expect(asked).toEqual([undefined, "usv/run-0001.mcap", undefined]));
    expect(store.getState().plan.calibrate).toBeNull();
  });

  it("reads the archives again on focus: a test flight that arrived meanwhile can be chosen", async () => {
    const archives = ["run-0000.mcap"];
    mount(archives);
    const picker = await screen.findByRole("combobox", { name: "Calibrate by archive" });
    const options = () => Array.from(picker.querySelectorAll("option"), (o) => o.textContent);
    await waitFor(() => expect(options()).toEqual(["no archive (declared ranges)", "run-0000.mcap"]));
    archives.push("test_flight.mcap");
    act(() => { fireEvent.focus(picker); });
    await waitFor(() => expect(options()).toEqual(["no archive (declared ranges)", "run-0000.mcap", "test_flight.mcap"]));
  });

  it("is there before the drone has an archive, and offers the first one on focus", async () => {
    const archives: string[] = [];
    const { asked } = mount(archives);
    await waitFor(() => expect(asked).toEqual([undefined]));
    const picker = await screen.findByRole("combobox", { name: "Calibrate by archive" });
    const options = () => Array.from(picker.querySelectorAll("option"), (o) => o.textContent);
    await waitFor(() => expect(options()).toEqual(["no archive (declared ranges)", "no archive of usv yet"]));
    archives.push("test_flight.mcap");
    act(() => { fireEvent.focus(picker); });
    await waitFor(() => expect(options()).toEqual(["no archive (declared ranges)", "test_flight.mcap"]));
  });
});
