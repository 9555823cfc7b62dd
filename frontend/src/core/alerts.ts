/**
 * Alerts: a THRESHOLD subscription marked `alert` in the model (docs/dsl.md,
 * "Alerts"), shown to the roles it names. Pure state, no React, no clock.
 *
 * What "active" means (docs/user-guide/operator.md, "Alerts"):
 * - The drone reports an alert's crossings both ways (its stream is
 *   THRESHOLD(BOTH level, hysteresis)); each event's direction is read from its
 *   value: above the level is an UP crossing (x > level + hysteresis), below a
 *   DOWN one (x < level - hysteresis).
 * - A crossing in the subscription's direction (UP, DOWN; BOTH: either) raises
 *   an alert, timed at the event's sample time (not when its window arrived),
 *   unless one of that direction is already active.
 * - A crossing the other way clears the subscription's active alerts ("signal
 *   back"): the hysteresis holds, since the drone only reports it past the band.
 *   With BOTH that crossing raises its own alert as it clears the previous one.
 * - The banner shows a view's alerts until acknowledged, those the signal has
 *   already cleared too ("back to normal", as alarm systems do: a short crossing
 *   is not missed). Acknowledged, an alert stays active and listed; a user may
 *   also clear it (no longer active). Both are this browser's.
 *
 * Memory is bounded: at most MAX_ALERTS are kept, the oldest inactive first.
 *
 * @example
 *   const rules = alertRules(model);
 *   let alerts = applyEvents([], rules[0], [{ t: 10, value: 0.7, event: true }], 10_500);
 *   bannerAlert(alerts, rules, "scientist") // the new alert, if rules[0] names the scientist
 */
import type { Sample } from "../dataSources/types";
import type { ModdModel as Model } from "./model.gen";
import { AGGREGATION } from "./contracts.gen";
import { precise } from "./numberFormat";
import type { ViewRole } from "./roles";

export type Direction = "up" | "down";

/** One alert subscription, as the model says it. */
export interface AlertRule {
  subscriber: string;
  topic: string;
  level: number;
  hysteresis: number;
  crossing: "up" | "down" | "both";
  roles: readonly string[];
}

export interface Alert {
  /** `<subscriber>@<event time>`: one event raises one alert, however often it is seen. */
  id: string;
  subscriber: string;
  direction: Direction;
  /** The sample that crossed, and its time on the drone's clock (seconds since the epoch). */
  value: number;
  t: number;
  /** When the browser received the event's window (ms since the epoch, the browser's clock). */
  receivedMs: number;
  /** When the SubBroker delivered the window (ns since the epoch), if it said. */
  deliveredNs?: number;
  acknowledged: boolean;
  active: boolean;
  /** Why it is no longer active: the signal crossed back, or a user cleared it. */
  cleared?: "signal" | "user";
}

/** Alerts kept at most (the oldest inactive ones go first). */
export const MAX_ALERTS = 200;

/** The model's alert subscriptions (THRESHOLD with `alert`). */
export function alertRules(model: Model): AlertRule[] {
  return model.subscribers.flatMap((s) => s.aggregation === AGGREGATION.THRESHOLD && s.alert?.length && s.level !== undefined && s.topic
    ? [{ subscriber: s.name, topic: s.topic, level: s.level, hysteresis: s.hysteresis ?? 0, crossing: s.crossing ?? "both", roles: s.alert }]
    : []);
}

/** Whether a view shows a rule's alerts (admin's "All roles" view shows every one). */
export function shownTo(rule: AlertRule, view: ViewRole): boolean {
  return view === "admin" || rule.roles.includes(view);
}

/** An event's direction: the drone reports a crossing once the sample is past the band, so its side says it. */
export function directionOf(rule: AlertRule, value: number): Direction {
  return value > rule.level ? "up" : "down";
}

function raises(rule: AlertRule, d: Direction): boolean {
  return rule.crossing === "both" || rule.crossing === d;
}

/** The newest crossing seen per subscriber (kept by the caller across batches). */
export type Newest = Map<string, { t: number; direction: Direction }>;

/**
 * The alerts after a batch of a rule's delivered samples (events only; in time order).
 * An event older than the newest crossing already seen (a window backfilled after the
 * link came back) is history: it is raised with its true time, for the banner, but
 * as already back to normal, and it clears nothing newer.
 */
export function applyEvents(alerts: readonly Alert[], rule: AlertRule, batch: readonly Sample[], receivedMs: number,
  newest: Newest = new Map()): Alert[] {
  let out = [...alerts];
  const events = batch.filter((s) => s.event).sort((a, b) => a.t - b.t);
  for (const e of events) {
    const d = directionOf(rule, e.value);
    const id = `${rule.subscriber}@${e.t}`;
    if (out.some((a) => a.id === id)) continue;
    const last = newest.get(rule.subscriber);
    const late = last !== undefined && last.t > e.t;
    if (!late) newest.set(rule.subscriber, { t: e.t, direction: d });
    // The way back clears what the other direction raised (with BOTH as well).
    out = out.map((a) => a.subscriber === rule.subscriber && a.active && a.direction !== d && a.t <= e.t
      ? { ...a, active: false, cleared: "signal" } : a);
    if (!raises(rule, d) || (!late && out.some((a) => a.subscriber === rule.subscriber && a.active && a.direction === d))) continue;
    out.push({ id, subscriber: rule.subscriber, direction: d, value: e.value, t: e.t, receivedMs,
      ...(e.deliveredNs !== undefined ? { deliveredNs: e.deliveredNs } : {}), acknowledged: false,
      ...(late ? { active: false, cleared: "signal" as const } : { active: true }) });
  }
  return bounded(out);
}

function bounded(alerts: Alert[]): Alert[] {
  if (alerts.length <= MAX_ALERTS) return alerts;
  const drop = new Set(alerts.filter((a) => !a.active).slice(0, alerts.length - MAX_ALERTS).map((a) => a.id));
  const kept = alerts.filter((a) => !drop.has(a.id));
  return kept.slice(Math.max(0, kept.length - MAX_ALERTS));
}

export function acknowledge(alerts: readonly Alert[], id: string): Alert[] {
  return alerts.map((a) => (a.id === id ? { ...a, acknowledged: true } : a));
}

export function clearAlert(alerts: readonly Alert[], id: string): Alert[] {
  return alerts.map((a) => (a.id === id && a.active ? { ...a, active: false, cleared: "user" } : a));
}

/** Active alerts a view lists, newest first. */
export function activeAlerts(alerts: readonly Alert[], rules: readonly AlertRule[], view: ViewRole): Alert[] {
  const shown = new Set(rules.filter((r) => view === "operator" || shownTo(r, view)).map((r) => r.subscriber));
  return alerts.filter((a) => a.active && shown.has(a.subscriber)).sort((a, b) => b.t - a.t);
}

/** What a view's banner holds: its alerts not yet acknowledged (active, or back to normal unseen), newest first. */
export function unacknowledged(alerts: readonly Alert[], rules: readonly AlertRule[], view: ViewRole): Alert[] {
  const mine = new Set(rules.filter((r) => shownTo(r, view)).map((r) => r.subscriber));
  return alerts.filter((a) => !a.acknowledged && a.cleared !== "user" && mine.has(a.subscriber)).sort((a, b) => b.t - a.t);
}

/** The alert a view's banner shows: its newest unacknowledged one, if any. */
export function bannerAlert(alerts: readonly Alert[], rules: readonly AlertRule[], view: ViewRole): Alert | null {
  return unacknowledged(alerts, rules, view)[0] ?? null;
}

/** Acknowledges every alert a view's banner holds. */
export function acknowledgeAll(alerts: readonly Alert[], rules: readonly AlertRule[], view: ViewRole): Alert[] {
  const ids = new Set(unacknowledged(alerts, rules, view).map((a) => a.id));
  return alerts.map((a) => (ids.has(a.id) ? { ...a, acknowledged: true } : a));
}

/** Event times of a subscriber's alerts (the chart's marks), seconds. */
export function alertTimes(alerts: readonly Alert[], subscriber: string): number[] {
  return alerts.filter((a) => a.subscriber === subscriber).map((a) => a.t);
}

/** The alert in words: "high_x: usv.accelerometer.accel_x above 0.5 (0.6342 at 12:00:01.250)". */
export function describeAlert(a: Alert, rule: AlertRule | undefined, time: (t: number) => string): string {
  const where = rule ? `${rule.topic} ${a.direction === "up" ? "above" : "below"} ${rule.level}` : a.direction;
  return `${a.subscriber}: ${where} (${precise(a.value, 4)} at ${time(a.t)})`;
}
