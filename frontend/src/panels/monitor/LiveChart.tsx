/**
 * One chart card of the monitor: one or more subscriptions on a TimeChart,
 * each with its last value, window and how stale it is; a subscription can
 * be taken off the chart, another watched one added to it; "Show values"
 * opens the chart's values as a table (ValuesTable).
 */
import { useEffect, useState, type ReactNode } from "react";
import { fixed, precise, whole } from "../../core/numberFormat";
import type { DataSource, Sample } from "../../dataSources/types";
import type { ViewWindow } from "../../core/chartData";
import { TimeChart, type ChartSeries } from "./TimeChart";
import { ValuesTable } from "./ValuesTable";

interface Props {
  source: DataSource;
  series: ChartSeries[];
  window: ViewWindow;
  onZoom: (from: number, to: number) => void;
  /** Watched subscriptions not on this chart, offered to add. */
  addable: string[];
  onAdd: (channel: string) => void;
  onRemove: (channel: string) => void;
  syncKey?: string;
  marker?: number | null;
  /** The clock "how old" is measured against (the playback cursor in a replay). */
  now?: number;
  /** Actions on this chart's subscriptions (the Monitor's "Fill gaps"). */
  tools?: ReactNode;
}

function useLast(source: DataSource, channel: string): [Sample | null, number] {
  const [last, setLast] = useState<Sample | null>(() => source.history(channel).at(-1) ?? null);
  const [count, setCount] = useState(() => source.history(channel).length);
  useEffect(() => {
    setLast(source.history(channel).at(-1) ?? null);
    setCount(source.history(channel).length);
    // Read back from the source: a playback seek delivers an empty batch and a shorter history.
    return source.subscribe(channel, () => {
      const h = source.history(channel);
      setLast(h.at(-1) ?? null);
      setCount(h.length);
    });
  }, [source, channel]);
  return [last, count];
}

function LastValue({ source, s, now }: { source: DataSource; s: ChartSeries; now: number }) {
  const [last, count] = useLast(source, s.channel);
  const age = last ? Math.max(now - last.t, 0) : null;
  return (
    <span className="chart-last-line">
      <strong>{s.title ?? s.channel}</strong> <span className="muted">{s.label}</span>
      <span className="chart-last" data-testid={`last-${s.channel}`}>
        {last ? <>last {precise(last.value, 5)}{s.unit ? ` ${s.unit}` : ""}{last.windowS ? ` over ${fixed(last.windowS, 2)} s` : ""}{last.count !== undefined ? ` (${whole(last.count)} samples)` : ""}</> : "waiting for values…"}
      </span>
      {last?.backfilled && <span className="backfilled" title="filled from the drone's archive after the link missed it; no live value is newer"> · backfilled</span>}
      {age !== null && <span className={age > 5 ? "stale" : "fresh"}> · {age < 1 ? "fresh" : `${fixed(age, 0)} s old`}</span>}
      <span className="muted"> · {count} kept</span>
    </span>
  );
}

export function LiveChart({ source, series, window, onZoom, addable, onAdd, onRemove, syncKey = "monitor", marker = null, now, tools }: Props) {
  const [clock, setClock] = useState(() => Date.now() / 1000);
  useEffect(() => {
    if (now !== undefined) return;
    const t = setInterval(() => setClock(Date.now() / 1000), 1000);
    return () => clearInterval(t);
  }, [now]);
  const id = series.map((s) => s.channel).join("+");
  return (
    <figure className="live-chart" data-testid={`chart-${id}`} aria-label={`Chart of ${series.map((s) => s.channel).join(", ")}`}>
      <figcaption>
        {series.map((s) => (
          <div key={s.channel}>
            <LastValue source={source} s={s} now={now ?? clock} />
            {series.length > 1 && <button className="link" aria-label={`Take ${s.channel} off this chart`} onClick={() => onRemove(s.channel)}>×</button>}
          </div>
        ))}
        {addable.length > 0 && (
          <select className="chart-pick" aria-label={`Add to the chart of ${series[0]?.channel ?? ""}`} value=""
            onChange={(e) => { if (e.target.value) onAdd(e.target.value); }}>
            <option value="">+ add to this chart…</option>
            {addable.map((c) => <option key={c} value={c}>{c}</option>)}
          </select>
        )}
        {tools}
      </figcaption>
      <TimeChart source={source} series={series} window={window} onZoom={onZoom} syncKey={syncKey} marker={marker} />
      <ValuesTable source={source} series={series} window={window} />
    </figure>
  );
}
