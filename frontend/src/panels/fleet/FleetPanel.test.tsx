// @vitest-environment jsdom
import { act, cleanup, fireEvent, render, screen, within } from "@testing-library/react";
import { afterEach, describe, expect, it, vi } from "vitest";
import type { Api } from "../../api/client";
import type { Deployment, Fleet, FleetDrone } from "../../api/types";
import { ServicesContext, type Services } from "../../app/services";
import { focusDrone, useDroneName } from "../../app/fleetFocus";
import type { DataSource, Sample } from "../../dataSources/types";
import type { ModdModel } from "../../core/model.gen";
import { scenario1 } from "../../core/testing/scenario1";
import { createEditorStore, loadRevision } from "../../editor/store";
import { EditorContext } from "../../editor/useEditor";
import FleetPanel from "./FleetPanel";

afterEach(() => { cleanup(); focusDrone(""); });
// jsdom draws nothing: the layout (fleetMap) is what the map says where each drone is
vi.spyOn(HTMLCanvasElement.prototype, "getContext").mockReturnValue(null);

const NAMES = ["usv1", "usv2", "usv3"];

/** Scenario 1 with a GNSS and its position subscriptions, flown by three vehicles. */
function campaign(): ModdModel {
  const m = scenario1();
  m.drone.sensors.push({ name: "gnss", variables: [{ name: "lat", unit: "degree_north" }, { name: "lon", unit: "degree_east" }] });
  m.subscribers.push(
    { name: "fix_lat", topic: "usv.gnss.lat", periodS: "1", aggregation: "LAST" },
    { name: "fix_lon", topic: "usv.gnss.lon", periodS: "1", aggregation: "LAST" },
  );
  m.campaign = { name: "lake", vehicles: NAMES.map((name, i) => ({ name, pubBroker: { endpoint: { host: "127.0.0.1", port: 7181 + i } } })) };
  return m;
}

function deployment(id: number, drone: string, revision: number, status = "acked"): Deployment {
  return { id, project_id: 7, revision, drone, requested_by: "op", requested_at: "", finished_at: "", status, reply: null, error: status === "acked" ? null : "NO_REPLY" };
}

function fleet(): Fleet {
  const drone = (name: string, i: number): FleetDrone => ({
    name, description: null, channel: i < 2 ? "ch1" : null,
    pub_broker: { endpoint: { host: "127.0.0.1", port: 7181 + i } }, sub_broker: { endpoint: { host: "127.0.0.1", port: 7272 } },
    deployment: deployment(10 + i, name, 2),
    status: i === 2 ? null : { link: "up", station: `st${i}`, time_ns: 3e9, last_data_ns: 2e9 },
  });
  return { campaign: "lake", drones: NAMES.map(drone), channels: { ch1: ["usv1", "usv2"] } };
}

/** A drone's stream holding one fix: latitude 45 + i/1000, longitude 6. */
function source(i: number): DataSource {
  const fix: Record<string, Sample[]> = { fix_lat: [{ t: 1, value: 45 + i / 1000 }], fix_lon: [{ t: 1, value: 6 }] };
  return {
    state: "open", subscribe: () => () => undefined, history: (c: string) => fix[c] ?? [], dropped: () => 0,
    onLinkStatus: () => () => undefined, onStateChange: () => () => undefined, close: () => undefined,
  } as unknown as DataSource;
}

function Shown() { return <span data-testid="shown">{useDroneName()}</span>; }

async function mount(role: "operator" | "scientist" = "operator") {
  const api = {
    fleet: vi.fn(async () => fleet()),
    listDeployments: vi.fn(async () => [deployment(12, "usv3", 2), deployment(11, "usv2", 2), deployment(10, "usv1", 2), deployment(3, "usv2", 1)]),
    deployFleet: vi.fn(async (_p: number, drones: string[], revision?: number) => drones.map((d, i) => deployment(20 + i, d, revision ?? 2, d === "usv3" ? "failed" : "acked"))),
    subscribeFleet: vi.fn(async () => NAMES.map((d) => ({ drone: d, topic: `${d}.gnss.lat`, status: d === "usv3" ? "NO_REPLY" : "ACCEPTED", key: d === "usv3" ? null : `modd/${d}/sub/x` }))),
  };
  const services = { api: api as unknown as Api, openStream: (d: string) => source(NAMES.indexOf(d)) } as unknown as Services;
  const store = createEditorStore(campaign(), role);
  loadRevision(store, { id: 7, name: "lake" }, 2, campaign());
  await act(async () => {
    render(<ServicesContext.Provider value={services}><EditorContext.Provider value={store}><FleetPanel /><Shown /></EditorContext.Provider></ServicesContext.Provider>);
  });
  return api;
}

describe("FleetPanel", () => {
  it("shows every drone on one map with its link, station and deployment", async () => {
    await mount();
    const canvas = screen.getByTestId("fleet-canvas");
    expect(canvas.dataset.drones).toBe("3");
    const placed = JSON.parse(canvas.dataset.placed ?? "[]") as Array<[string, number, number]>;
    expect(placed.map((p) => p[0])).toEqual(NAMES);
    expect(placed[0][2]).toBeGreaterThan(placed[2][2]); // usv3 is the northernmost: highest on the map
    const row = (n: string) => within(screen.getByTestId(`fleet-row-${n}`));
    expect(row("usv1").getByTestId("fleet-link").textContent).toBe("up");
    expect(row("usv2").getByTestId("fleet-station").textContent).toBe("st1");
    expect(row("usv3").getByTestId("fleet-link").textContent).toBe("not reporting");
    expect(row("usv1").getByTestId("fleet-deployed").textContent).toBe("r2 acked");
    expect(screen.getByText(/channel ch1: usv1, usv2/)).toBeTruthy();
  });

  it("deploys to the ticked drones at once and shows each one's answer; rolls one back alone", async () => {
    const api = await mount();
    fireEvent.click(screen.getByLabelText("Deploy to usv2"));
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: "Deploy revision 2 to 2 drones" })); });
    expect(api.deployFleet).toHaveBeenLastCalledWith(7, ["usv1", "usv3"], undefined);
    expect(screen.getByTestId("fleet-ack-usv1").textContent).toBe("usv1: revision 2 acked");
    expect(screen.getByTestId("fleet-ack-usv3").textContent).toContain("failed (NO_REPLY)");
    const rollback = within(screen.getByTestId("fleet-row-usv2")).getByRole("button", { name: "Roll back to r1" });
    await act(async () => { fireEvent.click(rollback); });
    expect(api.deployFleet).toHaveBeenLastCalledWith(7, ["usv2"], 1);
    const none = within(screen.getByTestId("fleet-row-usv1")).getByRole("button", { name: "Roll back" }) as HTMLButtonElement;
    expect(none.disabled).toBe(true); // only r2 ever ran on usv1
  });

  it("subscribes to one variable of every drone in one step, one answer per drone", async () => {
    const api = await mount("scientist");
    fireEvent.change(screen.getByLabelText("Variable"), { target: { value: "gnss.lat" } });
    fireEvent.change(screen.getByLabelText("Subscription name"), { target: { value: "x" } });
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: "Subscribe on every drone" })); });
    expect(api.subscribeFleet).toHaveBeenCalledWith(7, { variable: "gnss.lat", period_s: "1.0", aggregation: "AVERAGE", subscriber: "x" });
    expect(screen.getByTestId("fleet-sub-usv1").textContent).toBe("usv1: usv1.gnss.lat ACCEPTED on modd/usv1/sub/x");
    expect(screen.getByTestId("fleet-sub-usv3").textContent).toContain("NO_REPLY");
    expect((screen.getByRole("button", { name: /Deploy revision/ }) as HTMLButtonElement).disabled).toBe(true); // not an operator
  });

  it("Monitor shows one drone in the per-drone panels", async () => {
    await mount();
    expect(screen.getByTestId("shown").textContent).toBe("usv1"); // a campaign's first vehicle until one is chosen
    act(() => { fireEvent.click(within(screen.getByTestId("fleet-row-usv3")).getByRole("button", { name: "Monitor" })); });
    expect(screen.getByTestId("shown").textContent).toBe("usv3");
  });
});
