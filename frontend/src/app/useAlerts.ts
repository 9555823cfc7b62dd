/**
 * The workbench's alerts (core/alerts.ts) over the drone's live stream: one
 * store per stream, fed by the alert subscriptions' channels while the
 * workbench is open (AlertBanner watches them), read by the banner, the
 * Monitor's "Active alerts" and the charts' marks. Acknowledge and clear are
 * this browser's. The sound is off unless the user turns it on (kept in
 * localStorage).
 *
 * @example
 *   const { alerts, rules, acknowledge } = useAlerts();
 */
import { useEffect, useMemo, useSyncExternalStore } from "react";
import {
  acknowledge as ack, acknowledgeAll as ackAll, alertRules, applyEvents, clearAlert, type Alert, type AlertRule, type Newest,
} from "../core/alerts";
import type { DataSource } from "../dataSources/types";
import type { ViewRole } from "../core/roles";
import { useModel } from "../editor/useEditor";
import { useDroneStream } from "./useDroneStream";

class AlertStore {
  alerts: Alert[] = [];
  /** Each subscriber's newest crossing: a backfilled older one is history, not the state. */
  private newest: Newest = new Map();
  private listeners = new Set<() => void>();
  /** Raised alerts (for the sound), newest last. */
  onRaised = new Set<(a: Alert) => void>();

  subscribe = (l: () => void) => { this.listeners.add(l); return () => { this.listeners.delete(l); }; };
  snapshot = () => this.alerts;

  set(next: Alert[]): void {
    const known = new Set(this.alerts.map((a) => a.id));
    this.alerts = next;
    for (const a of next) if (!known.has(a.id)) this.onRaised.forEach((f) => f(a));
    this.listeners.forEach((l) => l());
  }

  /** Feeds a rule's channel into the store; returns the unsubscribe. */
  watch(source: DataSource, rule: AlertRule): () => void {
    this.set(applyEvents(this.alerts, rule, source.history(rule.subscriber), Date.now(), this.newest));
    return source.subscribe(rule.subscriber, (batch) => this.set(applyEvents(this.alerts, rule, batch, Date.now(), this.newest)));
  }
}

const stores = new WeakMap<DataSource, AlertStore>();
function storeFor(source: DataSource): AlertStore {
  let s = stores.get(source);
  if (!s) { s = new AlertStore(); stores.set(source, s); }
  return s;
}

export interface Alerts {
  alerts: readonly Alert[];
  rules: AlertRule[];
  acknowledge(id: string): void;
  /** Acknowledges every alert a view's banner holds. */
  acknowledgeAll(view: ViewRole): void;
  clear(id: string): void;
  /** Called for each alert raised from now on. */
  onRaised(f: (a: Alert) => void): () => void;
}

export function useAlerts(): Alerts {
  const model = useModel();
  const { source } = useDroneStream(model.drone.name);
  const store = storeFor(source);
  const alerts = useSyncExternalStore(store.subscribe, store.snapshot);
  const rulesKey = JSON.stringify(alertRules(model));
  const rules = useMemo(() => JSON.parse(rulesKey) as AlertRule[], [rulesKey]);
  return {
    alerts, rules,
    acknowledge: (id) => store.set(ack(store.alerts, id)),
    acknowledgeAll: (view) => store.set(ackAll(store.alerts, rules, view)),
    clear: (id) => store.set(clearAlert(store.alerts, id)),
    onRaised: (f) => { store.onRaised.add(f); return () => { store.onRaised.delete(f); }; },
  };
}

/** Keeps the alert subscriptions' channels open (once, in the workbench). */
export function useWatchAlerts(rules: readonly AlertRule[]): void {
  const model = useModel();
  const { source } = useDroneStream(model.drone.name);
  const key = JSON.stringify(rules);
  useEffect(() => {
    const store = storeFor(source);
    const offs = (JSON.parse(key) as AlertRule[]).map((r) => store.watch(source, r));
    return () => offs.forEach((off) => off());
  }, [source, key]);
}

const SOUND_KEY = "modd.alertSound";

export function soundOn(): boolean {
  try { return localStorage.getItem(SOUND_KEY) === "on"; } catch { return false; }
}

export function setSound(on: boolean): void {
  try { localStorage.setItem(SOUND_KEY, on ? "on" : "off"); } catch { /* private mode: this page only */ }
}

/** A short two-tone beep (Web Audio; nothing where the browser has none). */
export function beep(): void {
  const Ctx = window.AudioContext as typeof AudioContext | undefined;
  if (!Ctx) return;
  const ctx = new Ctx();
  [880, 660].forEach((hz, i) => {
    const osc = ctx.createOscillator();
    const gain = ctx.createGain();
    gain.gain.value = 0.15;
    osc.frequency.value = hz;
    osc.connect(gain).connect(ctx.destination);
    osc.start(ctx.currentTime + i * 0.18);
    osc.stop(ctx.currentTime + i * 0.18 + 0.15);
  });
  window.setTimeout(() => void ctx.close(), 800);
}
