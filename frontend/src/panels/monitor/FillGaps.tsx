/**
 * "Fill gaps": asks the drone for what the link missed of some subscriptions
 * (backfill from its archive, paced within the link's spare budget) and shows
 * the progress: windows done / total, bytes/s used against the pace, time left (from
 * the SubBroker's view of its queue at the link's measured pace, or what it waits for
 * instead of a number: "waiting for the drone's archive").
 * The Monitor puts one on each chart (the chart's subscriptions) and one for
 * the drone (every subscription of the model and the dynamic ones).
 * One backfill per subscription, started together; the bar sums them (a
 * subscription the drone refuses is named beside it). Only subscriptions of
 * the running plan can be filled (dynamic ones are not in the drone's plan).
 * Backfilled values arrive on the usual stream, marked `backfilled`: counted
 * here as they come (the chart draws them in place, marked). A running job
 * says what it waits for (the SubBroker's queue: "queued behind 3 jobs",
 * "waiting for the link", "paced at 600 B/s"), shown beside the bar. The
 * scientist and the operator both see it (roles.canFillGaps). Contract: talks
 * only through the services' api and the panel's data source; polls each
 * running backfill every POLL_MS.
 */
import { useEffect, useRef, useState } from "react";
import { fixed } from "../../core/numberFormat";
import { useServices } from "../../app/services";
import type { BackfillProgress } from "../../api/types";
import type { BackfillQueue } from "../../core/contracts.gen";
import { queueTimeLeft } from "./backfillQueue";
import type { DataSource } from "../../dataSources/types";

const POLL_MS = 500;

/** The fill's progress: the jobs' summed, and what it waits for when no time left is said. */
export interface FillProgress extends BackfillProgress {
  waiting: string | null;
}

interface Props {
  drone: string;
  source: DataSource;
  /** The subscriptions a click fills. */
  subscribers: string[];
  /** What is filled, in words ("sub_5", "drone usv"): names the region. */
  scope: string;
  /** Short form (on a chart): the bar and the counts on one line. */
  compact?: boolean;
}

/** What running backfills wait for, in a few words: one job's reason, or the reason of the
 * job on the link and how many are queued behind it. */
export function runningReason(all: readonly BackfillProgress[]): string | null {
  const reasons = all.filter((p) => p.status === "RUNNING" && p.reason).map((p) => p.reason as string);
  if (reasons.length <= 1) return reasons[0] ?? null;
  const queued = reasons.filter((r) => r.startsWith("queued behind")).length;
  const active = reasons.find((r) => !r.startsWith("queued behind"));
  return [active, queued ? `${queued} queued` : null].filter(Boolean).join(", ");
}

/**
 * The progress of several backfills as one: windows and bytes/s summed; the time left from
 * the SubBroker's view of its queue (``queue``, the newest polled: queueTimeLeft), with what
 * the fill waits for where it gives no number. Without a view, a lone job's own time left.
 */
export function sumProgress(all: readonly BackfillProgress[], queue: BackfillQueue | null = null): FillProgress | null {
  if (all.length === 0) return null;
  const sum = (f: (p: BackfillProgress) => number) => all.reduce((n, p) => n + f(p), 0);
  const running = all.filter((p) => p.status === "RUNNING");
  const done = all.some((p) => p.status === "DONE");
  // A failure decides only when nothing ran to the end (each failure is said beside the bar).
  const failed = done ? undefined : all.find((p) => p.status !== "RUNNING" && p.status !== "DONE");
  const left = queue
    ? queueTimeLeft(queue, new Set(running.map((p) => p.id ?? -1)))
    : { seconds: running.length === 1 ? running[0].seconds_left ?? null : null, waiting: null };
  return {
    status: running.length ? "RUNNING" : failed ? failed.status : "DONE",
    reason: running.length ? runningReason(all) : failed?.reason ?? null,
    windows: sum((p) => p.windows), windows_done: sum((p) => p.windows_done), windows_total: sum((p) => p.windows_total),
    duplicates: sum((p) => p.duplicates), bytes: sum((p) => p.bytes), seconds: Math.max(...all.map((p) => p.seconds)),
    bytes_per_s: sum((p) => p.bytes_per_s), rate_bps: Math.max(...all.map((p) => p.rate_bps)),
    seconds_left: running.length ? left.seconds : null,
    waiting: running.length && left.seconds == null ? left.waiting : null,
  };
}

export function FillGaps({ drone, source, subscribers, scope, compact = false }: Props) {
  const { api } = useServices();
  const [jobs, setJobs] = useState<Record<string, BackfillProgress>>({});
  const [error, setError] = useState<string | null>(null);
  const [marked, setMarked] = useState(0);
  const timers = useRef(new Set<number>());
  /** The SubBroker's view of its queue, from the newest answer (sumProgress). */
  const [queue, setQueue] = useState<BackfillQueue | null>(null);
  const key = subscribers.join(",");

  useEffect(() => () => { timers.current.forEach((t) => window.clearTimeout(t)); }, []);
  useEffect(() => {
    const offs = (key ? key.split(",") : []).map((sub) => source.subscribe(sub, (batch) => {
      const n = batch.filter((s) => s.backfilled).length;
      if (n) setMarked((m) => m + n);
    }));
    return () => offs.forEach((off) => off());
  }, [source, key]);

  const poll = (sub: string, id: number) => {
    const t = window.setTimeout(async () => {
      timers.current.delete(t);
      try {
        const p = await api.backfillProgress(drone, id);
        setJobs((j) => ({ ...j, [sub]: p }));
        if (p.queue) setQueue(p.queue);
        if (p.status === "RUNNING") poll(sub, id);
      } catch (err) {
        setError((err as Error).message);
      }
    }, POLL_MS);
    timers.current.add(t);
  };

  const start = async () => {
    setError(null);
    setMarked(0);
    setJobs({});
    setQueue(null);
    await Promise.all(subscribers.map(async (sub) => {
      try {
        const p = await api.startBackfill(drone, { subscriber: sub, gaps: true });
        setJobs((j) => ({ ...j, [sub]: p }));
        if (p.queue) setQueue(p.queue);
        if (p.status === "RUNNING" && p.id) poll(sub, p.id);
        else if (p.status !== "DONE") setError(`${sub}: ${p.status}${p.reason ? `: ${p.reason}` : ""}`);
      } catch (err) {
        setError(`${sub}: ${(err as Error).message}`);
      }
    }));
  };

  const progress = sumProgress(Object.values(jobs), queue);
  const running = progress?.status === "RUNNING";
  const total = progress?.windows_total ?? 0;
  return (
    <section className={compact ? "fill-gaps compact" : "fill-gaps"} aria-label={`Fill gaps: ${scope}`}>
      {!compact && <h3>Fill gaps</h3>}
      <button type="button" onClick={start} disabled={subscribers.length === 0 || running}
        title={`Ask the drone for what the link missed of ${subscribers.join(", ")}`}>Fill gaps</button>
      {!compact && <span className="muted"> {subscribers.length} subscription{subscribers.length === 1 ? "" : "s"}</span>}
      {progress && (
        <div role="status" aria-label="Backfill progress" data-testid="backfill-progress">
          <progress max={Math.max(total, 1)} value={total ? progress.windows_done : 1} />
          <span> {progress.windows_done}/{total} windows</span>
          <span className="muted"> · {fixed(progress.bytes_per_s, 0)} of {progress.rate_bps || "—"} B/s</span>
          {running && progress.seconds_left != null && <span className="muted" data-testid="backfill-left"> · {fixed(progress.seconds_left, 0)} s left</span>}
          {running && progress.waiting && <span className="muted" data-testid="backfill-left"> · time left: {progress.waiting}</span>}
          {running && progress.reason && <span className="muted" data-testid="backfill-reason"> · {progress.reason}</span>}
          <strong> · {progress.status === "DONE" ? `done: ${progress.windows} filled, ${progress.duplicates} duplicates` : progress.status.toLowerCase()}</strong>
          {marked > 0 && <span className="backfilled"> · {marked} backfilled values received</span>}
        </div>
      )}
      {error && <p className="error" role="alert">{error}</p>}
    </section>
  );
}
