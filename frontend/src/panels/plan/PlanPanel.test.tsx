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

function mount(plan: PlanJson | null, diagnostics = [] as Array<{ severity: "error"; message: string; pointer: string }>) {
  const store = createEditorStore(scenario1(), "designer");
  store.patch({ plan: { busy: false, error: null, result: { ok: plan !== null, plan, diagnostics, elapsed_ms: 12 } } });
  render(<EditorContext.Provider value={store}><PlanPanel /></EditorContext.Provider>);
  return store;
}

/** A link budget within its radio's rate (udp, 3600 B/s). */
const UDP_BUDGET = {
  transport: "udp" as const, rate_bps: 3600, max_packet: 1472, accepted_delay_s: 1,
  drone_to_base: 100.8, base_to_drone: 1.4, packets_per_s: 0.8, share: 0.028,
  delays_s: { sub_1: 1.03 }, over_budget: [], error: null,
};

describe("PlanPanel", () => {
  it("shows the planner's figures: hyperperiod, buffer sizes, delays, link cost", () => {
    mount(planJson as unknown as PlanJson);
    expect(screen.getByTestId("hyperperiod").textContent).toBe("2.0 s");
    expect(screen.getAllByTestId("buffer-size").map((c) => c.textContent)).toEqual(["28", "28", "6"]);
    expect(screen.getByRole("button", { name: "sub_1 (0.88 s)" })).toBeTruthy();
    expect(screen.getByText("14.88 kB/s")).toBeTruthy();
    expect(screen.getByRole("img", { name: /8 messages/ })).toBeTruthy();
  });

  it("selects a subscriber from its chip", () => {
    const store = mount(planJson as unknown as PlanJson);
    act(() => { fireEvent.click(screen.getByRole("button", { name: "sub_5 (0.01 s)" })); });
    expect(store.getState().wb.selection).toEqual(["sub:sub_5"]);
  });

  it("explains infeasibility", () => {
    const p = { ...(planJson as unknown as PlanJson), infeasible: [{ topic: "usv.accelerometer.accel_z", subscribers: ["sub_5"], reason: "period 0.1 is not a multiple of 0.04" }] };
    mount(p);
    expect(screen.getByRole("alert").textContent).toMatch(/sub_5\): period 0.1 is not a multiple/);
  });

  it("shows the link budget and the over-budget error naming the subscriptions", () => {
    const budget = {
      transport: "serial" as const, rate_bps: 60, max_packet: 252, accepted_delay_s: 1,
      drone_to_base: 83.45, base_to_drone: 0.733, packets_per_s: 0.85, share: 1.390833,
      delays_s: { sub_1: 2.7, sub_2: 2.7 }, over_budget: ["sub_4", "sub_2"],
      error: "the plan needs 83.4 B/s on the serial link, more than its 60 B/s; the subscriptions that exceed the budget: sub_4, sub_2",
      control: { status_period_s: 60, bytes_per_s: 1.85, packets_per_s: 0.05, bound_bytes_per_s: 5.033 },
    };
    const store = mount({ ...(planJson as unknown as PlanJson), link_budget: budget });
    expect(screen.getByTestId("transport").textContent).toBe("serial");
    expect(screen.getByTestId("budget-share").textContent).toBe("139.1 %");
    // the link's own STATUS and PONG, included in the figure on the wire
    const control = screen.getByTestId("control-rate");
    expect(control.textContent).toMatch(/of which control\s*about 1\.\d+ B\/s/);
    expect(control.title).toMatch(/STATUS every 60 s.*at most 5\.\d+ B\/s/);
    expect(screen.getByTestId("budget-error").textContent).toMatch(/more than its 60 B\/s.*sub_4, sub_2/);
    act(() => { fireEvent.click(screen.getByRole("button", { name: "sub_4" })); });
    expect(store.getState().wb.selection).toEqual(["sub:sub_4"]);
  });

  it("labels its two delays apart: the planner's schedule delay and the delay on the link", () => {
    mount({ ...(planJson as unknown as PlanJson), link_budget: UDP_BUDGET });
    expect(screen.queryByText("Max delay")).toBeNull();
    const schedule = screen.getByText("Max schedule delay").parentElement!;
    const link = screen.getByLabelText("Delay per subscription");
    expect(link.textContent).toMatch(/^Delay on the link \(.*after the schedule\)/);
    expect(schedule.title).toMatch(/buffer size × publisher period/);
    expect(link.title).toMatch(/air|rate/);
    expect(screen.getByRole("columnheader", { name: /schedule delay/ })).toBeTruthy();
  });

  it("shows no budget error within the budget", () => {
    mount({ ...(planJson as unknown as PlanJson), link_budget: UDP_BUDGET });
    expect(screen.getByTestId("transport").textContent).toBe("udp");
    expect(screen.queryByTestId("budget-error")).toBeNull();
  });

  it("lists the errors in words, once each, when the model cannot be planned", () => {
    const e = { severity: "error" as const, message: "should be non-empty", pointer: "/publishers/0/topics" };
    mount(null, [e, { ...e }]);
    expect(screen.getByRole("status").textContent).toMatch(/1 error/);
    expect(screen.getByRole("alert", { name: "Plan errors" }).textContent).toContain("publisher pub_1: topics: should be non-empty");
  });

  it("keeps the last valid plan greyed under the errors", () => {
    const store = createEditorStore(scenario1(), "designer");
    const plan = planJson as unknown as PlanJson;
    store.patch({ plan: { busy: false, error: null, lastValid: plan, result: { ok: false, plan: null, elapsed_ms: 3,
      diagnostics: [{ severity: "error", message: "required", pointer: "/subscribers/6/topic" }] } } });
    render(<EditorContext.Provider value={store}><PlanPanel /></EditorContext.Provider>);
    expect(screen.getByTestId("plan-stale")).toBeTruthy();
    expect(screen.getAllByTestId("buffer-size").map((c) => c.textContent)).toEqual(["28", "28", "6"]);
    expect(screen.getByRole("alert", { name: "Plan errors" }).textContent).toContain("subscriber sub_7: topic: required");
  });

  it("highlights what the last edit changed in the plan", () => {
    const store = createEditorStore(scenario1(), "designer");
    const before = planJson as unknown as PlanJson;
    const after = { ...before, hyperperiod_s: "10.0", delays: { ...before.delays, sub_3: "2.0" } };
    store.patch({ plan: { busy: false, error: null, lastValid: after, previous: before, result: { ok: true, plan: after, elapsed_ms: 3, diagnostics: [] } } });
    render(<EditorContext.Provider value={store}><PlanPanel /></EditorContext.Provider>);
    const changes = screen.getByRole("status", { name: "Plan changes" }).textContent;
    expect(changes).toContain("hyperperiod: 2.0 s → 10.0 s");
    expect(changes).toMatch(/sub_3 delay: [\d.]+ s → 2\.0 s/);
    expect(screen.getByTestId("hyperperiod").className).toBe("changed");
    expect(screen.getByRole("button", { name: "sub_3 (2.0 s)" }).className).toMatch(/changed/);
  });
});
