/**
 * Archive space on board, from the PubBroker's STATUS counters the SubBroker
 * relays (status `pubbroker`: `disk_free_mb`, `archive_rate_bps` — archive
 * bytes per second, 10 s average — and `archive_state`: 0 ok, 1 low space,
 * 2 disk full; docs/protocol.md). Pure: the Monitor shows what it returns.
 *
 * @example
 * archiveSpace({ disk_free_mb: 1024, archive_rate_bps: 2048, archive_state: 0 }).hoursLeft
 * // 145.6… (1 GiB at 2 KiB/s)
 */

export type ArchiveState = "ok" | "low" | "full" | "unknown";

export interface ArchiveSpace {
  state: ArchiveState;
  diskFreeMb: number | null;
  /** Archive bytes per second written lately. */
  rateBps: number | null;
  /** Hours until the disk is full at the current rate (null: unknown or not filling). */
  hoursLeft: number | null;
  /** Worth the operator's attention: low space, a full disk, or under WARN_HOURS left. */
  warn: boolean;
}

/** Fewer hours than this left at the current rate is a warning even before the threshold. */
export const WARN_HOURS = 2;

function finite(x: unknown): number | null {
  return typeof x === "number" && Number.isFinite(x) ? x : null;
}

export function archiveSpace(pubbroker: Record<string, unknown> | null | undefined): ArchiveSpace | null {
  if (!pubbroker) return null;
  const diskFreeMb = finite(pubbroker.disk_free_mb);
  const rateBps = finite(pubbroker.archive_rate_bps);
  const code = finite(pubbroker.archive_state);
  if (diskFreeMb === null && code === null) return null;
  const state: ArchiveState = code === 0 ? "ok" : code === 1 ? "low" : code === 2 ? "full" : "unknown";
  const hoursLeft = diskFreeMb !== null && rateBps !== null && rateBps > 0
    ? (diskFreeMb * 1024 * 1024) / rateBps / 3600
    : null;
  const warn = state === "low" || state === "full" || (hoursLeft !== null && hoursLeft < WARN_HOURS);
  return { state, diskFreeMb, rateBps, hoursLeft, warn };
}

/** "3 h 20 min", "45 min", "12 days" — for the Monitor's line. */
export function formatHours(hours: number): string {
  if (hours >= 48) return `${Math.floor(hours / 24)} days`;
  const h = Math.floor(hours);
  const m = Math.floor((hours - h) * 60);
  return h > 0 ? `${h} h ${m} min` : `${m} min`;
}
