/**
 * "Fill gaps": asks the drone for what the link missed of one subscription
 * (backfill from its archive, paced within the link's spare budget) and shows
 * the progress: windows done / total, bytes/s used against the pace, time left.
 * Backfilled values arrive on the usual stream, marked `backfilled`: counted
 * here as they come. Contract: talks only through the services' api and the
 * panel's data source; polls the progress every POLL_MS while it runs.
 */
import { useEffect, useRef, useState } from "react";
import { useServices } from "../../app/services";
import type { BackfillProgress } from "../../api/types";
import type { DataSource } from "../../dataSources/types";

const POLL_MS = 500;

interface Props {
  drone: string;
  source: DataSource;
  subscribers: string[];
}

export function FillGaps({ drone, source, subscribers }: Props) {
  const { api } = useServices();
  const [chosen, setChosen] = useState("");
  const [progress, setProgress] = useState<BackfillProgress | null>(null);
  const [error, setError] = useState<string | null>(null);
  const [marked, setMarked] = useState(0);
  const timer = useRef<number | undefined>(undefined);
  const subscriber = chosen || subscribers[0] || "";

  useEffect(() => () => window.clearTimeout(timer.current), []);
  useEffect(() => {
    if (!subscriber) return;
    return source.subscribe(subscriber, (batch) => {
      const n = batch.filter((s) => s.backfilled).length;
      if (n) setMarked((m) => m + n);
    });
  }, [source, subscriber]);

  const poll = (id: number) => {
    timer.current = window.setTimeout(async () => {
      try {
        const p = await api.backfillProgress(drone, id);
        setProgress(p);
        if (p.status === "RUNNING") poll(id);
      } catch (err) {
        setError((err as Error).message);
      }
    }, POLL_MS);
  };

  const start = async () => {
    setError(null);
    setMarked(0);
    try {
      const p = await api.startBackfill(drone, { subscriber, gaps: true });
      setProgress(p);
      if (p.status === "RUNNING" && p.id) poll(p.id);
      else if (p.status !== "DONE") setError(`${p.status}: ${p.reason ?? ""}`);
    } catch (err) {
      setError((err as Error).message);
    }
  };

  const running = progress?.status === "RUNNING";
  const total = progress?.windows_total ?? 0;
  return (
    <section className="fill-gaps" aria-label="Fill gaps">
      <h3>Fill gaps</h3>
      <select aria-label="Subscription to fill" value={subscriber} onChange={(e) => setChosen(e.target.value)}>
        {subscribers.map((s) => <option key={s}>{s}</option>)}
      </select>
      <button type="button" onClick={start} disabled={!subscriber || running}>Fill gaps</button>
      {progress && (
        <div role="status" aria-label="Backfill progress" data-testid="backfill-progress">
          <progress max={Math.max(total, 1)} value={total ? progress.windows_done : 1} />
          <span> {progress.windows_done}/{total} windows</span>
          <span className="muted"> · {progress.bytes_per_s.toFixed(0)} of {progress.rate_bps || "—"} B/s</span>
          {progress.seconds_left != null && running && <span className="muted"> · {progress.seconds_left.toFixed(0)} s left</span>}
          <strong> · {progress.status === "DONE" ? `done: ${progress.windows} filled, ${progress.duplicates} duplicates` : progress.status.toLowerCase()}</strong>
          {marked > 0 && <span className="backfilled"> · {marked} backfilled values received</span>}
        </div>
      )}
      {error && <p className="error" role="alert">{error}</p>}
    </section>
  );
}
