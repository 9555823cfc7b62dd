// @vitest-environment jsdom
import { afterEach, describe, expect, it } from "vitest";
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import PlanPanel from "./PlanPanel";
import { EditorContext } from "../../editor/useEditor";
import { createEditorStore } from "../../editor/store";
import { scenario1 } from "../../core/testing/scenario1";
import planJson from "../../core/testing/scenario1.plan.json";
import type { PlanJson } from "../../core/plan";

afterEach(cleanup);

type Radio = NonNullable<PlanJson["radio"]>;

// `modd plan --json` of scenario 1 with `radio = lora; sf = 7; battery = 50;` (costs cut to 3)
const refused: Radio = {
  kind: "lora", bytes_per_s: 81.6, packets_per_hour: 2880, air_time_s_per_hour: 502.088, duty_cycle: 0.01,
  duty_share: 13.94688, energy_j_per_hour: 160.643, battery_wh: 50, battery_share_per_hour: 0.000892,
  costs: [
    { subscription: "sub_5", bytes_per_s: 18.133, air_time_s_per_hour: 111.575 },
    { subscription: "sub_1", bytes_per_s: 11.333, air_time_s_per_hour: 69.734 },
    { subscription: "sub_2", bytes_per_s: 11.333, air_time_s_per_hour: 69.734 },
  ],
  error: "the plan transmits 502.1 s per hour on the lora radio, over its duty-cycle limit of 1 % (36.0 s per hour); the subscriptions that cost most: sub_5 111.6 s/h (18.1 B/s)",
  diagnostics: [{ pointer: "/subscribers/4", message: "sub_5 costs 111.6 s of air time per hour (18.1 B/s)" }],
  proposals: [
    { accepted_delay_s: 1, min_period_s: 8, max_delay_s: 0, bytes_per_s: 4, air_time_s_per_hour: 32.371, duty_share: 0.8992, energy_j_per_hour: 28.315, change: "accepted delay 1.0 s, every subscription's period at least 8.0 s" },
    { accepted_delay_s: 16, min_period_s: 4, max_delay_s: 16, bytes_per_s: 5.1, air_time_s_per_hour: 31.38, duty_share: 0.87168, energy_j_per_hour: 28.036, change: "accepted delay 16.0 s, every subscription's period at least 4.0 s" },
  ],
};

function mount(radio: Radio | undefined) {
  const store = createEditorStore(scenario1(), "designer");
  const plan = { ...(planJson as unknown as PlanJson), radio };
  store.patch({ plan: { busy: false, error: null, result: { ok: true, plan, diagnostics: [], elapsed_ms: 12 } } });
  render(<EditorContext.Provider value={store}><PlanPanel /></EditorContext.Provider>);
  return store;
}

describe("AirTime (the Plan panel's radio)", () => {
  it("shows air time, duty-cycle share, energy, the refusal and the proposals", () => {
    const store = mount(refused);
    expect(screen.getByTestId("radio-kind").textContent).toBe("lora");
    expect(screen.getByTestId("air-time").textContent).toBe("502.1 s");
    expect(screen.getByTestId("duty-share").textContent).toBe("1394.7 %");
    expect(screen.getByTestId("energy").textContent).toBe("160.6 J");
    expect(screen.getByTestId("battery-share").textContent).toBe("0.09 %");
    expect(screen.getByTestId("radio-error").textContent).toMatch(/Refused by the radio.*duty-cycle limit of 1 %/);
    const rows = screen.getAllByTestId("proposal").map((r) => r.textContent);
    expect(rows).toHaveLength(2);
    expect(rows[0]).toMatch(/at least 8\.0 s.*0\.0 s.*32\.4 s \(89\.9 %\).*28\.3 J/);
    act(() => { fireEvent.click(screen.getByRole("button", { name: "sub_5 (111.6 s/h)" })); });
    expect(store.getState().wb.selection).toEqual(["sub:sub_5"]);
  });

  it("says which figures are bounds and which are estimates (declared resolutions)", () => {
    mount({
      ...refused, figures: "estimate", air_time_bound_s_per_hour: 339.9, duty_share: 9.44,
      proposals: [{ ...refused.proposals[0], figures: "upper_bound", air_time_bound_s_per_hour: null }],
    });
    expect(screen.getByTestId("air-time").textContent).toBe("about 502.1 s");
    expect(screen.getByTestId("air-time-bound").textContent).toBe("at most 339.9 s");
    expect(screen.getByText(/At most, of the 1\.00 % duty cycle/)).toBeTruthy();
    expect(screen.getByTestId("energy").textContent).toBe("about 160.6 J");
    expect(screen.getAllByTestId("proposal")[0].textContent).toMatch(/at most 32\.4 s \(89\.9 %\)/);
  });

  it("a plan that fits: figures, no refusal, no proposals", () => {
    mount({ ...refused, duty_share: 0.5, error: null, proposals: [], costs: [] });
    expect(screen.getByTestId("duty-share").textContent).toBe("50.0 %");
    expect(screen.queryByTestId("radio-error")).toBeNull();
    expect(screen.queryAllByTestId("proposal")).toHaveLength(0);
  });

  it("nothing without a radio in the model", () => {
    mount(undefined);
    expect(screen.queryByLabelText("Radio air time and energy")).toBeNull();
  });
});
