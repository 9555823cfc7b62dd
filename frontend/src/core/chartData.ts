/**
 * Pure helpers behind the time charts: several series with their own
 * timestamps on one x axis, the visible time window (following the newest
 * value, or fixed after a zoom or a pan), and axis labels with units.
 *
 * @example
 *   alignSeries([[{ t: 1, value: 5 }], [{ t: 2, value: 7 }]])
 *   // [[1, 2], [5, null], [null, 7]]
 *   visibleRange({ follow: true, spanS: 60 }, 100) // [40, 100]: one point still gets a 60 s axis
 */
import type { Sample } from "../dataSources/types";

/** Follow the newest value over the last `spanS` seconds, or show [from, to] (after a zoom or pan). */
export type ViewWindow = { follow: true; spanS: number } | { follow: false; from: number; to: number };

export const DEFAULT_WINDOW: ViewWindow = { follow: true, spanS: 60 };

/** One x array (union of the timestamps, ascending) and one y array per series (null where it has no value). */
export function alignSeries(series: ReadonlyArray<readonly Sample[]>): [number[], ...Array<Array<number | null>>] {
  const xs = [...new Set(series.flatMap((s) => s.map((p) => p.t)))].sort((a, b) => a - b);
  const index = new Map(xs.map((t, i) => [t, i]));
  const ys = series.map((s) => {
    const y: Array<number | null> = new Array<number | null>(xs.length).fill(null);
    for (const p of s) y[index.get(p.t)!] = p.value;
    return y;
  });
  return [xs, ...ys];
}

/**
 * The x range to draw: a fixed window as is; a following window ends at the
 * newest value and spans `spanS` (never the years uPlot picks for one point).
 */
export function visibleRange(w: ViewWindow, last: number | null): [number, number] {
  if (!w.follow) return [w.from, w.to];
  const end = last ?? Date.now() / 1000;
  return [end - w.spanS, end];
}

/** Zooms a range around its centre (factor < 1 zooms in). */
export function zoomRange([from, to]: [number, number], factor: number): ViewWindow {
  const c = (from + to) / 2;
  const half = Math.max(((to - from) * factor) / 2, 0.05);
  return { follow: false, from: c - half, to: c + half };
}

/** Moves a range by a share of its width (negative: back in time). */
export function panRange([from, to]: [number, number], share: number): ViewWindow {
  const d = (to - from) * share;
  return { follow: false, from: from + d, to: to + d };
}

/** The unit of a topic's values as an axis reads it; COUNT counts samples whatever the unit. */
export function unitLabel(unit: string | undefined, aggregation?: string): string {
  if (aggregation === "COUNT") return "samples";
  if (!unit || unit === "NONE") return "";
  const words: Record<string, string> = {
    METER: "m", METER_PER_SECOND: "m/s", METER_PER_SECOND_SQUARED: "m/s²", DEGREE_CELSIUS: "°C",
    RADIAN: "rad", RADIAN_PER_SECOND: "rad/s", BAR: "bar", LITER: "L", GRAM: "g",
  };
  return words[unit] ?? unit;
}

/** The y axis label of a chart: its distinct units joined. */
export function axisLabel(units: readonly string[]): string {
  return [...new Set(units.filter(Boolean))].join(" · ");
}
