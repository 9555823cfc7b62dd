/**
 * What the monitor charts, per drone: charts as lists of subscriptions, the
 * shared time window, and the dynamic subscriptions with their topic and
 * aggregation. Kept for the page's lifetime (module state), so leaving the
 * panel or redeploying does not reset the charts.
 */
import { useCallback, useState } from "react";
import { DEFAULT_WINDOW, type ViewWindow } from "../../core/chartData";
import { chartsAdd, chartsMove, chartsRemove, chartsSplit } from "../../core/chartLayout";

export interface DynamicSub { topic: string; period_s: string; aggregation: string }

export interface ChartLayout {
  charts: string[][];
  win: ViewWindow;
  dynamic: Record<string, DynamicSub>;
}

const kept = new Map<string, ChartLayout>();

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
