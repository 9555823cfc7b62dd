/**
 * A chart's values as table rows: the text alternative of a Monitor chart
 * (panels/monitor/ValuesTable), where a scientist reads exact values, each
 * window's start and end and whether it was backfilled from the drone's
 * archive. Pure: no DOM, no clock.
 */
import type { Sample } from "../dataSources/types";

export interface ValueRow {
  channel: string;
  /** Start of the window, seconds since the epoch (unknown when the value carries no window length). */
  start: number | null;
  /** End of the window (the value's time), seconds since the epoch. */
  end: number;
  value: number;
  count: number | null;
  backfilled: boolean;
}

export interface TableRows {
  rows: ValueRow[];
  /** Rows in the range (and the filter) before the limit cut the oldest off. */
  total: number;
}

/**
 * Rows of every channel whose window ends in `[from, to]`, oldest first; at
 * most `limit`, the newest kept. `backfilledOnly`: only the values that came
 * from a backfill.
 *
 *   tableRows([{ channel: "sub_5", samples: [{ t: 2, value: 1, windowS: 0.25 }] }], [0, 10])
 *   // → { rows: [{ channel: "sub_5", start: 1.75, end: 2, value: 1, count: null, backfilled: false }], total: 1 }
 */
export function tableRows(channels: ReadonlyArray<{ channel: string; samples: readonly Sample[] }>,
  [from, to]: readonly [number, number], { backfilledOnly = false, limit = 2000 } = {}): TableRows {
  const rows: ValueRow[] = [];
  for (const { channel, samples } of channels) {
    for (const s of samples) {
      if (s.t < from || s.t > to || (backfilledOnly && !s.backfilled)) continue;
      rows.push({
        channel, end: s.t, value: s.value, backfilled: s.backfilled === true,
        start: s.windowS !== undefined ? s.t - s.windowS : null, count: s.count ?? null,
      });
    }
  }
  rows.sort((a, b) => a.end - b.end || a.channel.localeCompare(b.channel));
  const total = rows.length;
  return { rows: rows.slice(Math.max(0, total - Math.max(0, limit))), total };
}

/** A time of day with milliseconds, 24 h, in the browser's time zone: "14:03:07.250". */
export function clockTime(seconds: number): string {
  const d = new Date(Math.round(seconds * 1000));
  const two = (n: number) => String(n).padStart(2, "0");
  return `${two(d.getHours())}:${two(d.getMinutes())}:${two(d.getSeconds())}.${String(d.getMilliseconds()).padStart(3, "0")}`;
}

/** A value as the table prints it: 7 significant digits (a float32 holds about that many), no trailing zeros. */
export function formatValue(v: number): string {
  if (!Number.isFinite(v)) return String(v);
  return String(Number(v.toPrecision(7)));
}
