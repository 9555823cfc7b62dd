/**
 * The plug-and-play instruments' health (modd-sensors on board, forwarded by
 * the PubBroker in STATUS; the SubBroker's status `sensors`, docs/sensors.md
 * "Health"), one row per sensor for the operator.
 *
 * A sensor is flagged when its device is closed (unplugged, renumbered), it
 * fell silent, it gave only bad lines, or only sentences saying they have no
 * fix (a GNSS receiver without satellites: docs/sensors.md "Validity"). The last value's time is the
 * drone's clock, as the instrument's values are stamped.
 *
 * @example
 *   instrumentsHealth({ ctd: { state: 1, lines_ok: 9, lines_bad: 0, last_value_ms: 1999000 } })
 *   // [{ name: "ctd", state: "open", linesOk: 9, linesBad: 0, lastValueMs: 1999000, ... }]
 */
import type { SensorHealth } from "./contracts.gen";
import { clockUtc } from "./numberFormat";

export type InstrumentState = "closed" | "open" | "silent" | "unknown";
const STATES: InstrumentState[] = ["closed", "open", "silent"];  // the protocol's codes

export interface InstrumentHealth {
  name: string;
  state: InstrumentState;
  linesOk: number;
  linesBad: number;
  reconnects: number;
  /** When the last value was received on board, ms since the epoch (null: none yet). */
  lastValueMs: number | null;
  values: number;
  /** Modbus requests with no reply, and exception replies. */
  timeouts: number;
  exceptions: number;
  silences: number;
  /** Mapped fields of sentences that said they had no fix (none taken). */
  noFix: number;
  /** Good lines the model maps nothing of. */
  ignored: number;
  /** Why the operator should look, in words (null: nothing to say). */
  alert: string | null;
}

/** A counter as the drone sent it: a whole number ≥ 0, else 0 (a string, NaN, -3, 2^63 beyond 2^53). */
const count = (x: unknown): number =>
  typeof x === "number" && Number.isFinite(x) && x >= 0 ? Math.min(Math.trunc(x), Number.MAX_SAFE_INTEGER) : 0;
/** The largest ms since the epoch a Date holds. */
const MAX_DATE_MS = 8.64e15;

/** Rows sorted by sensor name; any status a drone sends gives rows (a field
 * it cannot be is shown as none). */
export function instrumentsHealth(sensors: Record<string, SensorHealth> | null | undefined): InstrumentHealth[] {
  if (!sensors || typeof sensors !== "object" || Array.isArray(sensors)) return [];
  return Object.keys(sensors).sort().map((name) => {
    const raw: unknown = sensors[name];
    const h = (raw && typeof raw === "object" ? raw : {}) as Partial<SensorHealth>;
    const state = (Number.isInteger(h.state) ? STATES[h.state as number] : undefined) ?? "unknown";
    const last = count(h.last_value_ms);
    const row = {
      name, state,
      linesOk: count(h.lines_ok), linesBad: count(h.lines_bad), reconnects: count(h.reconnects),
      lastValueMs: last > 0 && last <= MAX_DATE_MS ? last : null,
      values: count(h.values), timeouts: count(h.timeouts), exceptions: count(h.exceptions),
      silences: count(h.silences), noFix: count(h.no_fix), ignored: count(h.ignored),
    };
    return { ...row, alert: alertOf(row) };
  });
}

function alertOf(h: Omit<InstrumentHealth, "alert">): string | null {
  if (h.state === "closed") return "device closed (unplugged or lost)";
  const noFix = h.noFix > 0 ? ` (${h.noFix} fields refused: the receiver said it had no fix)` : "";
  if (h.state === "silent") return `silent: no value for 3 periods${noFix}`;
  if (h.values === 0 && h.linesBad > 0) return "only bad lines (wrong baud rate or format?)";
  if (h.values === 0 && h.noFix > 0) return `no fix yet${noFix}`;
  return null;
}

/** A time of day in UTC, to the second: "10:15:02 UTC" ("—" for no valid time). */
export function formatClock(ms: number): string {
  return clockUtc(ms);
}
