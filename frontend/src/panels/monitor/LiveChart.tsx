/**
 * A live uPlot chart of one subscription: fed by the data source, redrawn at
 * most once per animation frame; shows the last value, its window and how
 * stale it is.
 */
import { useEffect, useRef, useState } from "react";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import type { DataSource, Sample } from "../../dataSources/types";

interface Props {
  source: DataSource;
  subscriber: string;
  label: string;
}

export function LiveChart({ source, subscriber, label }: Props) {
  const host = useRef<HTMLDivElement>(null);
  const [last, setLast] = useState<Sample | null>(null);
  const [count, setCount] = useState(0);
  const [now, setNow] = useState(() => Date.now() / 1000);

  useEffect(() => {
    const el = host.current;
    if (!el) return;
    const data = (): uPlot.AlignedData => {
      const h = source.history(subscriber);
      return [h.map((s) => s.t), h.map((s) => s.value)];
    };
    const plot = new uPlot({
      width: Math.max(el.clientWidth, 200), height: 140,
      scales: { x: { time: true } },
      legend: { show: false },
      series: [{}, { label, stroke: "#2563eb", width: 1.5, points: { show: true, size: 4 } }],
      axes: [{ stroke: "#475569" }, { stroke: "#475569", size: 56 }],
    }, data(), el);
    let frame = 0;
    const off = source.subscribe(subscriber, (batch) => {
      setLast(batch[batch.length - 1]);
      setCount((c) => c + batch.length);
      if (!frame) frame = requestAnimationFrame(() => { frame = 0; plot.setData(data()); });
    });
    const ro = new ResizeObserver(() => plot.setSize({ width: Math.max(el.clientWidth, 200), height: 140 }));
    ro.observe(el);
    const h = source.history(subscriber);
    if (h.length) setLast(h[h.length - 1]);
    return () => { off(); ro.disconnect(); cancelAnimationFrame(frame); plot.destroy(); };
  }, [source, subscriber, label]);

  useEffect(() => {
    const t = setInterval(() => setNow(Date.now() / 1000), 1000);
    return () => clearInterval(t);
  }, []);

  const age = last ? Math.max(now - last.t, 0) : null;
  return (
    <figure className="live-chart" data-testid={`chart-${subscriber}`}>
      <figcaption>
        <strong>{subscriber}</strong> <span className="muted">{label}</span>
        <span className="chart-last" data-testid={`last-${subscriber}`}>
          {last ? <>last {last.value.toPrecision(5)}{last.windowS ? ` over ${last.windowS.toFixed(2)} s` : ""}{last.count !== undefined ? ` (${last.count} samples)` : ""}</> : "waiting for values…"}
        </span>
        {age !== null && <span className={age > 5 ? "stale" : "fresh"}> · {age < 1 ? "fresh" : `${age.toFixed(0)} s old`}</span>}
        <span className="muted"> · {count} received</span>
      </figcaption>
      <div ref={host} className="chart-host" />
    </figure>
  );
}
