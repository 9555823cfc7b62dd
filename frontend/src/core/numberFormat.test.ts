import { describe, expect, it } from "vitest";
import { clockUtc, DASH, finite, fixed, localTime, precise, whole } from "./numberFormat";
import { instrumentsHealth, formatClock } from "./instrumentHealth";
import { formatRate } from "./plan";
import { formatAge } from "./linkHealth";

/** What a drone could send where a number is expected. */
const HOSTILE: unknown[] = [
  2 ** 53, 2 ** 63, -(2 ** 63), -1, 1e308, -1e308, Infinity, -Infinity, NaN,
  "NaN", "1e400", "12", "", null, undefined, {}, [], true, { valueOf: () => { throw new Error("x"); } },
];

describe("total formatters", () => {
  it("give text for every input, never an exception", () => {
    for (const x of HOSTILE) {
      for (const f of [
        () => fixed(x, 1), () => fixed(x, 500), () => precise(x, 5), () => precise(x, 0), () => whole(x),
        () => clockUtc(x), () => localTime(x), () => formatClock(x as number),
        () => formatRate(x as number), () => formatAge(x as number),
      ]) {
        expect(typeof f(), String(x)).toBe("string");
      }
    }
  });

  it("show what cannot be shown as a dash", () => {
    expect(clockUtc(2 ** 53)).toBe(DASH);
    expect(clockUtc(2 ** 63)).toBe(DASH);
    expect(clockUtc(NaN)).toBe(DASH);
    expect(clockUtc("1999000")).toBe(DASH);
    expect(fixed("12", 1)).toBe(DASH);
    expect(precise(Infinity, 5)).toBe(DASH);
    expect(whole(null)).toBe(DASH);
    expect(localTime(1e300)).toBe(DASH);
    expect(formatRate(NaN)).toBe(DASH);
    expect(formatAge("x" as unknown as number)).toBe(DASH);
  });

  it("keep the figures that are good", () => {
    expect(clockUtc(Date.UTC(2026, 0, 2, 10, 15, 2))).toBe("10:15:02 UTC");
    expect(clockUtc(-1000)).toBe("23:59:59 UTC");  // before the epoch: still a time
    expect(fixed(12.345, 1, " ms")).toBe("12.3 ms");
    expect(precise(3.14159, 3)).toBe("3.14");
    expect(whole(7.9)).toBe("7");
    expect(finite(0)).toBe(0);
    expect(formatRate(1500)).toBe("1.50 kB/s");
    expect(formatAge(75)).toBe("1 min 15 s");
  });
});

describe("instrumentsHealth", () => {
  it("takes any status a drone sends", () => {
    const rows = instrumentsHealth({
      huge: { state: 1, last_value_ms: 2 ** 63, lines_ok: "9", lines_bad: -3 },
      gone: null, text: "open", neg: { state: -1, last_value_ms: -5 },
    } as never);
    expect(rows.map((r) => r.name)).toEqual(["gone", "huge", "neg", "text"]);
    for (const r of rows) expect(typeof formatClock(r.lastValueMs ?? 0)).toBe("string");
    expect(rows.find((r) => r.name === "huge")?.lastValueMs).toBeNull();  // no valid time
    expect(instrumentsHealth("garbage" as never)).toEqual([]);
  });
});
