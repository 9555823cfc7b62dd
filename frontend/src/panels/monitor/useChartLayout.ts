/**
 * What the monitor charts, per drone: charts as lists of subscriptions, the
 * shared time window, and the dynamic subscriptions with their topic and
 * aggregation. Kept for the page's lifetime (module state), so leaving the
 * panel or redeploying does not reset the charts; the charted channels stay
 * subscribed on the workbench's stream meanwhile (keepSubscribed).
 */
import { useCallback, useState } from "react";
import { DEFAULT_WINDOW, type ViewWindow } from "../../core/chartData";
import type { DataSource } from "../../dataSources/types";
import { chartsAdd, chartsMove, chartsRemove, chartsSplit } from "../../core/chartLayout";

export interface DynamicSub { topic: string; period_s: string; aggregation: string }

export interface ChartLayout {
  charts: string[][];
  win: ViewWindow;
  dynamic: Record<string, DynamicSub>;
}

const kept = new Map<string, ChartLayout>();

/** Channels kept subscribed on each source while charted, panel shown or not (so charts have no gaps). */
const held = new WeakMap<DataSource, Map<string, () => void>>();

/** Keeps exactly `channels` subscribed on `source` until the next call; the source's close ends them all. */
export function keepSubscribed(source: DataSource, channels: readonly string[]): void {
  let map = held.get(source);
  if (!map) { map = new Map(); held.set(source, map); }
  for (const [c, off] of map) if (!channels.includes(c)) { off(); map.delete(c); }
  for (const c of channels) if (!map.has(c)) map.set(c, source.subscribe(c, () => undefined));
}

export function useChartLayout(drone: string, initial: string[]) {
  const [state, setState] = useState<ChartLayout>(() => kept.get(drone) ?? { charts: initial.map((c) => [c]), win: DEFAULT_WINDOW, dynamic: {} });
  const update = useCallback((f: (s: ChartLayout) => ChartLayout) => {
    setState((s) => { const n = f(s); kept.set(drone, n); return n; });
  }, [drone]);
  return {
    state,
    toggle: (c: string) => update((s) => ({ ...s, charts: s.charts.flat().includes(c) ? chartsRemove(s.charts, c) : chartsAdd(s.charts, c) })),
    moveTo: (c: string, chart: number) => update((s) => ({ ...s, charts: chartsMove(s.charts, c, chart) })),
    split: (c: string) => update((s) => ({ ...s, charts: chartsSplit(s.charts, c) })),
    setWindow: (win: ViewWindow) => update((s) => ({ ...s, win })),
    addDynamic: (c: string, d: DynamicSub) => update((s) => ({ ...s, dynamic: { ...s.dynamic, [c]: d }, charts: chartsAdd(s.charts, c) })),
  };
}
