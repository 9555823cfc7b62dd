import { describe, expect, it } from "vitest";
import type { Sample } from "../dataSources/types";
import { toSamples } from "../dataSources/WebSocketSource";
import {
  MAX_ALERTS, acknowledge, acknowledgeAll, activeAlerts, alertRules, alertTimes, applyEvents, bannerAlert, clearAlert, describeAlert, type Alert, type AlertRule, type Newest,
} from "./alerts";
import type { ModdModel as Model } from "./model.gen";
import { localTimeMs } from "./numberFormat";

const rule = (crossing: AlertRule["crossing"], roles = ["scientist", "operator"]): AlertRule =>
  ({ subscriber: "hi", topic: "usv.accelerometer.accel_x", level: 0.5, hysteresis: 0.1, crossing, roles });

/** The drone's THRESHOLD(BOTH L, h) restated (docs/planning.md): the events of a sampled signal. */
function crossings(xs: Array<[number, number]>, level: number, h: number): Array<Sample & { dir: "up" | "down" }> {
  const out: Array<Sample & { dir: "up" | "down" }> = [];
  let above: boolean | null = null;
  for (const [t, x] of xs) {
    if (above === null) { above = x > level; continue; }
    if (!above && x > level + h) { above = true; out.push({ t, value: x, event: true, dir: "up" }); }
    else if (above && x < level - h) { above = false; out.push({ t, value: x, event: true, dir: "down" }); }
  }
  return out;
}

/** A swinging signal sampled at 25 Hz for `s` seconds (the demo's accel_x: 0.8 sin(2π 0.3 t)). */
const swing = (s: number): Array<[number, number]> =>
  Array.from({ length: s * 25 }, (_, k) => [1000 + k / 25, 0.8 * Math.sin(2 * Math.PI * 0.3 * (k / 25))]);

/** Feeds events in 1 s windows, as the SubBroker delivers them. */
function feed(r: AlertRule, events: Sample[]): Alert[] {
  let alerts: Alert[] = [];
  for (let w = 1000; w < 1031; w += 1) {
    alerts = applyEvents(alerts, r, events.filter((e) => e.t >= w && e.t < w + 1), (w + 1) * 1000);
  }
  return alerts;
}

describe("alerts", () => {
  it("UP: each up crossing raises one alert at its sample time; the next down crossing clears it", () => {
    const events = crossings(swing(30), 0.5, 0.1);
    const ups = events.filter((e) => e.dir === "up");
    const alerts = feed(rule("up"), events);
    expect(ups.length).toBeGreaterThan(5);
    expect(alerts.map((a) => a.t)).toEqual(ups.map((e) => e.t));
    for (const a of alerts) {
      const back = events.find((e) => e.dir === "down" && e.t > a.t);
      expect(a.active).toBe(back === undefined);
      if (back) expect(a.cleared).toBe("signal");
    }
    expect(alerts.every((a) => a.direction === "up" && a.value > 0.6)).toBe(true);
  });

  it("DOWN raises on the way down only; BOTH raises on each crossing and clears the one before", () => {
    const events = crossings(swing(30), 0.5, 0.1);
    expect(feed(rule("down"), events).map((a) => a.t)).toEqual(events.filter((e) => e.dir === "down").map((e) => e.t));
    const both = feed(rule("both"), events);
    expect(both.map((a) => a.t)).toEqual(events.map((e) => e.t));
    expect(both.filter((a) => a.active)).toHaveLength(1);
  });

  it("an event seen twice raises one alert; a late window keeps the event's true time", () => {
    const e: Sample = { t: 1000.2, value: 0.7, event: true, deliveredNs: 1_000_900_000_000 };
    let alerts = applyEvents([], rule("up"), [e], 1_060_000); // arrived a minute later (the link was lost)
    alerts = applyEvents(alerts, rule("up"), [e], 1_061_000);
    expect(alerts).toHaveLength(1);
    expect(alerts[0]).toMatchObject({ t: 1000.2, receivedMs: 1_060_000, deliveredNs: 1_000_900_000_000, active: true });
    expect(applyEvents([], rule("up"), [{ t: 1, value: 0.9 }], 0)).toEqual([]); // not an event: a plain value
  });

  it("an outage's crossings backfilled after newer live ones are raised as history, not as the state", () => {
    const newest: Newest = new Map();
    const up = rule("up");
    // live: up at 10 (raised), then the link is lost; after it, live down at 16 clears it
    let alerts = applyEvents([], up, [{ t: 10, value: 0.7, event: true }], 10_100, newest);
    alerts = applyEvents(alerts, up, [{ t: 16, value: 0.3, event: true }], 16_100, newest);
    expect(alerts.filter((a) => a.active)).toHaveLength(0);
    // backfilled: the outage's down at 12 and up at 14 (older than the live down at 16)
    alerts = applyEvents(alerts, up, [{ t: 12, value: 0.3, event: true }, { t: 14, value: 0.8, event: true }], 20_000, newest);
    const late = alerts.find((a) => a.t === 14);
    expect(late).toMatchObject({ active: false, cleared: "signal", acknowledged: false, receivedMs: 20_000 });
    expect(activeAlerts(alerts, [up], "operator")).toEqual([]);
    expect(bannerAlert(alerts, [up], "scientist")?.t).toBe(14); // seen in the banner, back to normal
    // and a late down never clears a newer live alert
    alerts = applyEvents(alerts, up, [{ t: 30, value: 0.9, event: true }], 30_100, newest);
    alerts = applyEvents(alerts, up, [{ t: 25, value: 0.2, event: true }], 31_000, newest);
    expect(activeAlerts(alerts, [up], "operator").map((a) => a.t)).toEqual([30]);
  });

  it("shows the banner to the roles that asked; the operator's list holds every active alert", () => {
    const rules = [rule("up", ["scientist"])];
    const alerts = applyEvents([], rules[0], [{ t: 5, value: 0.7, event: true }], 0);
    expect(bannerAlert(alerts, rules, "scientist")?.id).toBe("hi@5");
    expect(bannerAlert(alerts, rules, "designer")).toBeNull();
    expect(bannerAlert(alerts, rules, "admin")?.id).toBe("hi@5");
    expect(activeAlerts(alerts, rules, "operator").map((a) => a.id)).toEqual(["hi@5"]);
    expect(activeAlerts(alerts, rules, "integrator")).toEqual([]);
  });

  it("acknowledged: still active, no banner; cleared: no longer active", () => {
    const rules = [rule("up")];
    let alerts = applyEvents([], rules[0], [{ t: 5, value: 0.7, event: true }], 0);
    alerts = acknowledge(alerts, "hi@5");
    expect(bannerAlert(alerts, rules, "scientist")).toBeNull();
    expect(activeAlerts(alerts, rules, "operator")).toHaveLength(1);
    alerts = applyEvents(alerts, rules[0], [{ t: 6, value: 0.3, event: true }, { t: 7, value: 0.8, event: true }], 0);
    expect(alerts.map((a) => [a.id, a.active, a.cleared])).toEqual([["hi@5", false, "signal"], ["hi@7", true, undefined]]);
    // back to normal but not yet seen: still in the banner until acknowledged
    alerts = applyEvents(alerts, rules[0], [{ t: 8, value: 0.3, event: true }], 0);
    expect(bannerAlert(alerts, rules, "scientist")?.id).toBe("hi@7");
    expect(activeAlerts(alerts, rules, "operator")).toEqual([]);
    alerts = acknowledgeAll(alerts, rules, "scientist");
    expect(bannerAlert(alerts, rules, "scientist")).toBeNull();
    alerts = applyEvents(alerts, rules[0], [{ t: 9, value: 0.7, event: true }], 0);
    alerts = clearAlert(alerts, "hi@9");
    expect(activeAlerts(alerts, rules, "operator")).toEqual([]);
    expect(alerts.at(-1)?.cleared).toBe("user");
    expect(bannerAlert(alerts, rules, "scientist")).toBeNull();
    expect(alertTimes(alerts, "hi")).toEqual([5, 7, 9]);
  });

  it("keeps at most MAX_ALERTS, the oldest inactive first", () => {
    const events = crossings(Array.from({ length: 2000 }, (_, k): [number, number] => [k, k % 2 ? 1 : 0]), 0.5, 0.1);
    const alerts = applyEvents([], rule("up"), events, 0);
    expect(alerts).toHaveLength(MAX_ALERTS);
    expect(alerts.filter((a) => a.active)).toHaveLength(1);
    expect(alerts.at(-1)?.t).toBe(events.filter((e) => e.dir === "up").at(-1)?.t);
  });

  it("says an alert in words, its value to 4 digits", () => {
    const [a] = applyEvents([], rule("up"), [{ t: 5, value: 0.6797314882, event: true }], 0);
    expect(describeAlert(a, rule("up"), () => "T")).toBe("hi: usv.accelerometer.accel_x above 0.5 (0.6797 at T)");
    expect(localTimeMs(new Date(2026, 11, 5, 14, 5, 9, 250).getTime() / 1000)).toBe("14:05:09.250");
  });

  it("reads the alert subscriptions of a model", () => {
    const model = { subscribers: [
      { name: "hi", topic: "usv.a.x", periodS: "1.0", aggregation: "THRESHOLD", level: 0.5, crossing: "up", alert: ["operator"] },
      { name: "plain", topic: "usv.a.x", periodS: "1.0", aggregation: "THRESHOLD", level: 0.5 },
    ] } as unknown as Model;
    expect(alertRules(model)).toEqual([{ subscriber: "hi", topic: "usv.a.x", level: 0.5, hysteresis: 0, crossing: "up", roles: ["operator"] }]);
  });

  it("an event window's values come at their own sample times (event_ns)", () => {
    const s = toSamples({ start_ns: 10e9, end_ns: 11e9, value: [0.7, 0.3], count: 2, event_ns: [10_250_000_000, 10_750_000_000], delivered_ns: 11_100_000_000 });
    expect(s.map((x) => [x.t, x.value, x.event, x.deliveredNs])).toEqual([[10.25, 0.7, true, 11.1e9], [10.75, 0.3, true, 11.1e9]]);
  });
});
