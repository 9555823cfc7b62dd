/**
 * A uPlot chart of one or more channels of a DataSource (live subscriptions,
 * or an archive played back): time on x in local time, the values' units on
 * y, redrawn at most once per animation frame. The visible window comes from
 * outside (shared by every chart of a panel); dragging across a chart zooms
 * every chart to that range; the cursor is shared by all charts with the
 * same `syncKey`.
 *
 * Gaps: where windows of a subscription are missing (an outage), its line
 * breaks (a null point at the first missing window's time; the period comes
 * from the subscription). Backfilled values sit in place among the live ones
 * (the source keeps them in time order) and are marked: a second series per
 * channel draws them as large hollow amber points, legend "backfilled". The
 * caption says it in words (missing windows, backfilled values), since the
 * canvas holds no text.
 *
 * Quality flags: a window the backend flagged suspect or bad (QARTOD, by the
 * deployed project's tests: docs/user-guide/datasets.md, "Quality flags") is
 * marked by a red ring, legend "QC suspect/bad", counted in the caption.
 */
import { useEffect, useRef } from "react";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import type { DataSource } from "../../dataSources/types";
import { alertTime } from "../../app/AlertBanner";
import { alignWithGaps, axisLabel, flaggedSeries, gapSummary, qcSummary, visibleRange, type ViewWindow } from "../../core/chartData";

export interface ChartSeries {
  channel: string;
  /** The series' name on the chart (a playback names it by its topic, core/topicLabel); default the channel. */
  title?: string;
  label: string;
  unit: string;
  /** Seconds between windows (the subscription's period): where values are missing, the line breaks. */
  periodS?: number;
  /** Its alerts' times (core/alerts: the crossing samples' times), drawn as marks. */
  alerts?: number[];
}

const BACKFILLED = "#d97706";
const FLAGGED_RING = "#b91c1c";
const ALERT = "#b45309";

const COLOURS = ["#2563eb", "#dc2626", "#15803d", "#9333ea", "#0891b2", "#4d7c0f"];

interface Props {
  source: DataSource;
  series: ChartSeries[];
  window: ViewWindow;
  onZoom: (from: number, to: number) => void;
  syncKey: string;
  height?: number;
  /** A playback cursor to draw as a vertical line (seconds), if any. */
  marker?: number | null;
}

export function TimeChart({ source, series, window: view, onZoom, syncKey, height = 150, marker = null }: Props) {
  const host = useRef<HTMLDivElement>(null);
  const info = useRef<HTMLSpanElement>(null);
  const gaps = useRef<HTMLSpanElement>(null);
  const plotRef = useRef<uPlot | null>(null);
  const viewRef = useRef(view);
  viewRef.current = view;
  const markerRef = useRef(marker);
  markerRef.current = marker;
  const zoomRef = useRef(onZoom);
  zoomRef.current = onZoom;
  const key = series.map((s) => `${s.channel}|${s.title ?? ""}|${s.label}|${s.unit}|${s.periodS ?? ""}`).join(";");
  const marks = series.flatMap((s) => s.alerts ?? []);
  const marksRef = useRef(marks);
  marksRef.current = marks;
  const marksKey = marks.join(",");

  useEffect(() => {
    const el = host.current;
    if (!el) return;
    const data = (): uPlot.AlignedData => {
      const channels = series.map((s) => ({ samples: source.history(s.channel), periodS: s.periodS }));
      const qc = qcSummary(channels);
      if (gaps.current) gaps.current.textContent = gapSummary(channels) + (qc ? ` · ${qc}` : "");
      const aligned = alignWithGaps(channels);
      return [...aligned, ...flaggedSeries(channels, aligned[0])] as uPlot.AlignedData;
    };
    const lastT = () => Math.max(...series.map((s) => source.history(s.channel).at(-1)?.t ?? -Infinity));
    const range = (): [number, number] => {
      const last = lastT();
      return visibleRange(viewRef.current, Number.isFinite(last) ? last : null);
    };
    const plot = new uPlot({
      width: Math.max(el.clientWidth, 200), height,
      scales: { x: { time: true, range: () => range() } },
      legend: { show: true, live: true },
      cursor: { sync: { key: syncKey, setSeries: false }, drag: { x: true, y: false, setScale: false } },
      series: [
        { label: "time" },
        ...series.flatMap((s, i): uPlot.Series[] => [
          {
            label: s.title ?? (s.unit ? `${s.channel} (${s.unit})` : s.channel), stroke: COLOURS[i % COLOURS.length], width: 1.5,
            spanGaps: false, points: { show: true, size: 4 },
          },
          {
            label: series.length > 1 ? `backfilled (${s.channel})` : "backfilled", stroke: BACKFILLED, width: 0,
            paths: () => null, points: { show: true, size: 9, width: 2, stroke: BACKFILLED, fill: "#fff7ed" },
          },
        ]),
        // After every channel's pair (alignWithGaps), one series per channel: its flagged windows.
        ...series.map((s): uPlot.Series => ({
          label: series.length > 1 ? `QC suspect/bad (${s.channel})` : "QC suspect/bad", stroke: FLAGGED_RING, width: 0,
          paths: () => null, points: { show: true, size: 12, width: 2, stroke: FLAGGED_RING, fill: "transparent" },
        })),
      ],
      axes: [
        { stroke: "#475569", label: "local time", labelSize: 16 },
        { stroke: "#475569", size: 56, label: axisLabel(series.map((s) => s.unit)), labelSize: 16 },
      ],
      hooks: {
        // The axis as drawn, in words (the canvas holds no text a reader or a test can get at).
        setScale: [(u, scale) => {
          const min = u.scales.x.min;
          const max = u.scales.x.max;
          if (scale !== "x" || !info.current || min == null || max == null) return;
          const t = (s: number) => new Date(s * 1000).toLocaleTimeString();
          info.current.textContent = `time ${t(min)} – ${t(max)} (${(max - min).toFixed(1)} s)`;
        }],
        setSelect: [(u) => {
          if (u.select.width < 3) return;
          const from = u.posToVal(u.select.left, "x");
          const to = u.posToVal(u.select.left + u.select.width, "x");
          u.setSelect({ left: 0, top: 0, width: 0, height: 0 }, false);
          zoomRef.current(from, to);
        }],
        draw: [(u) => drawAlertMarks(u, marksRef.current), (u) => {
          const m = markerRef.current;
          if (m === null) return;
          const x = u.valToPos(m, "x", true);
          const ctx = u.ctx;
          ctx.save();
          ctx.strokeStyle = "#be185d";
          ctx.lineWidth = 2;
          ctx.beginPath();
          ctx.moveTo(x, u.bbox.top);
          ctx.lineTo(x, u.bbox.top + u.bbox.height);
          ctx.stroke();
          ctx.restore();
        }],
      },
    }, data(), el);
    plotRef.current = plot;
    let frame = 0;
    const redraw = () => {
      if (!frame) frame = requestAnimationFrame(() => { frame = 0; plot.setData(data()); });
    };
    const offs = series.map((s) => source.subscribe(s.channel, redraw));
    const ro = new ResizeObserver(() => plot.setSize({ width: Math.max(el.clientWidth, 200), height }));
    ro.observe(el);
    return () => { offs.forEach((off) => off()); ro.disconnect(); cancelAnimationFrame(frame); plot.destroy(); plotRef.current = null; };
    // eslint-disable-next-line react-hooks/exhaustive-deps
  }, [source, key, syncKey, height]);

  // A new window (zoom, pan, follow) or playback cursor: redraw with the same data.
  useEffect(() => {
    const plot = plotRef.current;
    if (plot) plot.setData(plot.data);
  }, [view, marker, marksKey]);

  const units = axisLabel(series.map((s) => s.unit));
  return (
    <>
      <div ref={host} className="chart-host" />
      <div className="chart-axes muted" data-testid="chart-axes">
        <span ref={info} /> · values{units ? ` in ${units}` : " (no unit)"}
        {" · "}<span ref={gaps} data-testid="chart-gaps" />
        {marks.length > 0 && <span data-testid="chart-alerts"> · {marks.length} alert{marks.length > 1 ? "s" : ""} marked, last at {alertTime(Math.max(...marks))}</span>}
      </div>
    </>
  );
}

/** An alert's mark: a dashed amber line at the crossing sample's time, a triangle on top. */
function drawAlertMarks(u: uPlot, times: readonly number[]): void {
  const ctx = u.ctx;
  ctx.save();
  ctx.strokeStyle = ALERT;
  ctx.fillStyle = ALERT;
  ctx.lineWidth = 2;
  ctx.setLineDash([4, 4]);
  for (const t of times) {
    const x = u.valToPos(t, "x", true);
    if (x < u.bbox.left || x > u.bbox.left + u.bbox.width) continue;
    ctx.beginPath();
    ctx.moveTo(x, u.bbox.top);
    ctx.lineTo(x, u.bbox.top + u.bbox.height);
    ctx.stroke();
    ctx.beginPath();
    ctx.moveTo(x - 5, u.bbox.top);
    ctx.lineTo(x + 5, u.bbox.top);
    ctx.lineTo(x, u.bbox.top + 8);
    ctx.fill();
  }
  ctx.restore();
}
