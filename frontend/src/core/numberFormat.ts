/**
 * Total formatters for figures that come from a drone or the network: any
 * input — a huge, negative or non-finite number, a string, null, an object —
 * gives text, never an exception. What cannot be shown is "—" (DASH).
 *
 * @example
 *   fixed(12.345, 1, " ms")   // "12.3 ms"
 *   fixed("12", 1)            // "—"
 *   clockUtc(2 ** 53)         // "—"  (beyond the dates JavaScript holds)
 */

export const DASH = "—";
/** The largest |ms since the epoch| a Date holds (ECMA-262: 100,000,000 days). */
const MAX_DATE_MS = 8.64e15;

/** ``x`` when it is a finite number, else null. */
export function finite(x: unknown): number | null {
  return typeof x === "number" && Number.isFinite(x) ? x : null;
}

/** ``x`` with ``digits`` decimals and ``unit``; DASH when not a finite number. */
export function fixed(x: unknown, digits: number, unit = ""): string {
  const n = finite(x);
  if (n === null) return DASH;
  const d = Math.min(20, Math.max(0, Math.trunc(digits)));
  return `${n.toFixed(d)}${unit}`;
}

/** ``x`` to ``digits`` significant digits; DASH when not a finite number. */
export function precise(x: unknown, digits: number): string {
  const n = finite(x);
  return n === null ? DASH : n.toPrecision(Math.min(21, Math.max(1, Math.trunc(digits))));
}

/** A whole count (a counter from a drone); DASH when not a finite number. */
export function whole(x: unknown): string {
  const n = finite(x);
  return n === null ? DASH : String(Math.trunc(n));
}

function dateOf(ms: unknown): Date | null {
  const n = finite(ms);
  return n === null || Math.abs(n) > MAX_DATE_MS ? null : new Date(n);
}

/** A time of day in UTC, to the second: "10:15:02 UTC"; DASH for no valid time. */
export function clockUtc(ms: unknown): string {
  const d = dateOf(ms);
  return d === null ? DASH : `${d.toISOString().slice(11, 19)} UTC`;
}

/** The local time of day of ``seconds`` since the epoch; DASH for no valid time. */
export function localTime(seconds: unknown): string {
  const s = finite(seconds);
  const d = s === null ? null : dateOf(s * 1000);
  return d === null ? DASH : d.toLocaleTimeString();
}

/** The local time of day of ``seconds`` to the millisecond, 24-hour: "14:05:09.250"; DASH for no valid time. */
export function localTimeMs(seconds: unknown): string {
  const s = finite(seconds);
  const d = s === null ? null : dateOf(s * 1000);
  if (d === null) return DASH;
  const two = (n: number) => String(n).padStart(2, "0");
  return `${two(d.getHours())}:${two(d.getMinutes())}:${two(d.getSeconds())}.${String(d.getMilliseconds()).padStart(3, "0")}`;
}
