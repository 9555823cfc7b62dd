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
import { AGGREGATION } from "./contracts.gen";

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

/** A chart's channel as the chart reads it: its samples (time order) and the subscription's period, if known. */
export interface ChannelData {
  samples: readonly Sample[];
  /** Seconds between two windows of the subscription; without it no gap is seen. */
  periodS?: number;
}

/** A hole longer than this many periods is a gap (ALL spreads a window's samples inside it). */
const GAP_PERIODS = 1.5;

/** Where windows are missing: [time of the last value before, time of the next value, windows missing]. */
export function findGaps(samples: readonly Sample[], periodS?: number): Array<[number, number, number]> {
  const gaps: Array<[number, number, number]> = [];
  if (!periodS || periodS <= 0) return gaps;
  for (let i = 1; i < samples.length; i++) {
    const dt = samples[i].t - samples[i - 1].t;
    if (dt > GAP_PERIODS * periodS) gaps.push([samples[i - 1].t, samples[i].t, Math.max(1, Math.round(dt / periodS) - 1)]);
  }
  return gaps;
}

/**
 * uPlot data for channels that may have gaps and backfilled values: x is the
 * union of the times plus one point inside each gap (the first missing
 * window's time); per channel two y arrays, its values (null at its own gaps,
 * so the line breaks there, and undefined where another channel has a point,
 * which uPlot joins across) and its backfilled values alone (to mark them).
 *
 * @example
 *   alignWithGaps([{ samples: [{ t: 1, value: 5 }, { t: 4, value: 7, backfilled: true }], periodS: 1 }])
 *   // [[1, 2, 4], [5, null, 7], [undefined, undefined, 7]]
 */
export function alignWithGaps(channels: readonly ChannelData[]): [number[], ...Array<Array<number | null | undefined>>] {
  const holes = channels.map((c) => findGaps(c.samples, c.periodS).map(([from]) => from + c.periodS!));
  const xs = [...new Set([...channels.flatMap((c) => c.samples.map((p) => p.t)), ...holes.flat()])].sort((a, b) => a - b);
  const index = new Map(xs.map((t, i) => [t, i]));
  const ys: Array<Array<number | null | undefined>> = [];
  channels.forEach((c, k) => {
    const y = new Array<number | null | undefined>(xs.length).fill(undefined);
    const marked = new Array<number | null | undefined>(xs.length).fill(undefined);
    for (const t of holes[k]) y[index.get(t)!] = null;
    for (const p of c.samples) {
      y[index.get(p.t)!] = p.value;
      if (p.backfilled) marked[index.get(p.t)!] = p.value;
    }
    ys.push(y, marked);
  });
  return [xs, ...ys];
}

/**
 * The gaps of what this page saw live: from a channel's first live (not backfilled)
 * value on. A fill brings windows from before the page opened too (the mission's
 * older gaps); the stretch between those and the first live value was delivered
 * before the page opened, not missed, and is no gap to count.
 */
export function liveGaps(c: ChannelData): Array<[number, number, number]> {
  const first = c.samples.findIndex((s) => !s.backfilled);
  return findGaps(first > 0 ? c.samples.slice(first) : c.samples, c.periodS);
}

/** In words, for a chart's caption: "2 windows missing in 1 gap · 5 backfilled". */
export function gapSummary(channels: readonly ChannelData[]): string {
  const gaps = channels.flatMap(liveGaps);
  const missing = gaps.reduce((n, g) => n + g[2], 0);
  const filled = channels.reduce((n, c) => n + c.samples.filter((s) => s.backfilled).length, 0);
  const words = gaps.length === 0 ? "no gap" : `${missing} window${missing === 1 ? "" : "s"} missing in ${gaps.length} gap${gaps.length === 1 ? "" : "s"}`;
  return `${words} · ${filled} backfilled`;
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
  if (aggregation === AGGREGATION.COUNT) return "samples";
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

/** QARTOD's flags a chart marks: SUSPECT (3) and FAIL (4). */
export const FLAGGED = new Set([3, 4]);

/**
 * Per channel, the values of its windows the backend flagged suspect or bad
 * (QARTOD 3 or 4) at the times `xs` (alignWithGaps's), undefined elsewhere:
 * a series the chart draws as marks.
 */
export function flaggedSeries(channels: readonly ChannelData[], xs: readonly number[]): Array<Array<number | undefined>> {
  const index = new Map(xs.map((t, i) => [t, i]));
  return channels.map((c) => {
    const y = new Array<number | undefined>(xs.length).fill(undefined);
    for (const p of c.samples) if (p.qc !== undefined && FLAGGED.has(p.qc)) y[index.get(p.t)!] = p.value;
    return y;
  });
}

/** In words, for the caption: "2 flagged (QARTOD: 1 suspect, 1 bad)", or "" when none is. */
export function qcSummary(channels: readonly ChannelData[]): string {
  const all = channels.flatMap((c) => c.samples);
  const suspect = all.filter((s) => s.qc === 3).length, bad = all.filter((s) => s.qc === 4).length;
  return suspect + bad === 0 ? "" : `${suspect + bad} flagged (QARTOD: ${suspect} suspect, ${bad} bad)`;
}
