/**
 * "Show values": a Monitor chart as a table (its text alternative, and where
 * a scientist reads exact values): one row per delivered window in the
 * chart's time window, oldest first — window start and end (local time, ms),
 * value, samples aggregated, and whether it was backfilled from the drone's
 * archive ("Backfilled only" keeps those). Closed by default; while open it
 * re-reads the source at most every REFRESH_MS. Each row also carries its
 * exact figures as data attributes (`data-start`, `data-end` in seconds since
 * the epoch, `data-value`) for tools that read the page.
 * Contract: reads only the panel's data source (history + subscribe).
 */
import { useEffect, useId, useState } from "react";
import type { DataSource } from "../../dataSources/types";
import { visibleRange, type ViewWindow } from "../../core/chartData";
import { clockTime, formatValue, tableRows } from "../../core/valueTable";
import type { ChartSeries } from "./TimeChart";

const REFRESH_MS = 500;
/** Rows shown at most (the newest): a long window of fast subscriptions holds thousands. */
export const ROW_LIMIT = 2000;

interface Props {
  source: DataSource;
  series: ChartSeries[];
  window: ViewWindow;
  /** Rows shown at most (the newest). */
  limit?: number;
}

export function ValuesTable({ source, series, window: view, limit = ROW_LIMIT }: Props) {
  const [open, setOpen] = useState(false);
  const [backfilledOnly, setBackfilledOnly] = useState(false);
  const [, setTick] = useState(0);
  const id = useId();
  const key = series.map((s) => s.channel).join(",");

  useEffect(() => {
    if (!open) return;
    let timer: ReturnType<typeof setTimeout> | null = null;
    const bump = () => {
      timer ??= setTimeout(() => { timer = null; setTick((n) => n + 1); }, REFRESH_MS);
    };
    const offs = series.map((s) => source.subscribe(s.channel, bump));
    return () => { offs.forEach((off) => off()); if (timer) clearTimeout(timer); };
    // eslint-disable-next-line react-hooks/exhaustive-deps
  }, [open, source, key]);

  const names = series.map((s) => s.channel).join(", ");
  const toggle = (
    <button className="link" aria-expanded={open} aria-controls={id} onClick={() => setOpen(!open)}>
      {open ? "Hide values" : "Show values"}
    </button>
  );
  if (!open) return <div className="values-table">{toggle}</div>;

  const channels = series.map((s) => ({ channel: s.channel, samples: source.history(s.channel) }));
  const newest = Math.max(...channels.map((c) => c.samples.at(-1)?.t ?? -Infinity));
  const range = visibleRange(view, Number.isFinite(newest) ? newest : null);
  const { rows, total } = tableRows(channels, range, { backfilledOnly, limit });
  const multi = series.length > 1;
  const units = [...new Set(series.map((s) => s.unit).filter(Boolean))];
  const shown = total > rows.length ? `the newest ${rows.length} of ${total}` : String(total);
  return (
    <div className="values-table">
      {toggle}
      <div id={id}>
        <label className="values-filter">
          <input type="checkbox" checked={backfilledOnly} onChange={(e) => setBackfilledOnly(e.target.checked)} /> Backfilled only
        </label>
        <table aria-label={`Values of ${names}`}>
          <caption data-testid="values-caption">
            {series.map((s) => `${s.channel}: ${s.label}`).join("; ")}
            {" · "}windows ending {clockTime(range[0])} – {clockTime(range[1])} · {shown} {backfilledOnly ? "backfilled " : ""}values
          </caption>
          <thead>
            <tr>
              {multi && <th scope="col">Subscription</th>}
              <th scope="col">Window start</th>
              <th scope="col">Window end</th>
              <th scope="col">Value{units.length === 1 ? ` (${units[0]})` : ""}</th>
              <th scope="col">Samples</th>
              <th scope="col">Backfilled</th>
            </tr>
          </thead>
          <tbody>
            {rows.map((r) => (
              <tr key={`${r.channel}@${r.end}:${r.value}`} className={r.backfilled ? "backfilled" : undefined}
                data-channel={r.channel} data-start={r.start ?? ""} data-end={r.end} data-value={r.value}>
                {multi && <td>{r.channel}</td>}
                <td>{r.start === null ? "—" : clockTime(r.start)}</td>
                <td>{clockTime(r.end)}</td>
                <td className="num">{formatValue(r.value)}</td>
                <td className="num">{r.count ?? "—"}</td>
                <td>{r.backfilled ? "backfilled" : "live"}</td>
              </tr>
            ))}
            {rows.length === 0 && (
              <tr><td colSpan={multi ? 6 : 5} className="muted">No {backfilledOnly ? "backfilled " : ""}value in this time window.</td></tr>
            )}
          </tbody>
        </table>
      </div>
    </div>
  );
}
