/**
 * The time left of a fill, from the SubBroker's view of its backfill queue (the `queue` of a
 * running job's progress; docs/subbroker.md, "The queue's view and the time left"): each of
 * our jobs' rest in full and, of every other job, as much as ours (the queue serves its
 * owners and their jobs in turn), at the link's measured pace. No number where it cannot
 * be computed: the job on the link waits for the drone's archive or for the link, or the
 * pace is not measured yet; what it waits for is said instead. The same rule as the
 * SubBroker's own (runtime/python/src/modd/subbroker/backfill_view.py, time_left).
 */
import type { BackfillQueue } from "../../core/contracts.gen";

export interface TimeLeft {
  /** Seconds until our jobs are done; null when it cannot be computed. */
  seconds: number | null;
  /** What the fill waits for when there is no number ("waiting for the drone's archive"). */
  waiting: string | null;
}

const WAITS: [string, string][] = [
  ["waiting_link", "waiting for the link"],
  ["waiting_archive", "waiting for the drone's archive"],
  ["unanswered", "waiting for the drone's answer"],
  ["busy", "the drone is busy"],
];

export function queueTimeLeft(queue: BackfillQueue | null | undefined, ours: ReadonlySet<number>): TimeLeft {
  const jobs = queue?.jobs ?? [];
  const mine = jobs.filter((j) => ours.has(j.id));
  if (mine.length === 0) return { seconds: null, waiting: queue && queue.more > 0 ? `queued behind ${jobs.length}+ jobs` : null };
  for (const [state, why] of WAITS) if (jobs.some((j) => j.state === state)) return { seconds: null, waiting: why };
  if (jobs.some((j) => j.send_s == null)) return { seconds: null, waiting: "measuring the pace" };
  const own = mine.reduce((n, j) => n + (j.send_s ?? 0), 0);
  const others = jobs.filter((j) => !ours.has(j.id)).reduce((n, j) => n + Math.min(j.send_s ?? 0, own), 0);
  return { seconds: own + others, waiting: null };
}
