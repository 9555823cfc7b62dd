import { describe, expect, it } from "vitest";
import { clockTime, formatValue, tableRows } from "./valueTable";

describe("tableRows", () => {
  const a = [
    { t: 10, value: 1, windowS: 0.25, count: 6 },
    { t: 10.25, value: 2, windowS: 0.25, backfilled: true },
    { t: 10.5, value: 3, windowS: 0.25 },
  ];
  const b = [{ t: 10.25, value: 7 }];

  it("keeps the windows ending in the range, oldest first, channels interleaved by time", () => {
    const { rows, total } = tableRows([{ channel: "a", samples: a }, { channel: "b", samples: b }], [10.1, 10.5]);
    expect(total).toBe(3);
    expect(rows.map((r) => [r.channel, r.end, r.value])).toEqual([["a", 10.25, 2], ["b", 10.25, 7], ["a", 10.5, 3]]);
    expect(rows[0]).toMatchObject({ start: 10, backfilled: true, count: null });
    expect(rows[1]).toMatchObject({ start: null, backfilled: false });
  });

  it("filters to the backfilled values and keeps the newest rows under the limit", () => {
    expect(tableRows([{ channel: "a", samples: a }], [0, 20], { backfilledOnly: true }).rows.map((r) => r.value)).toEqual([2]);
    const cut = tableRows([{ channel: "a", samples: a }], [0, 20], { limit: 2 });
    expect(cut.total).toBe(3);
    expect(cut.rows.map((r) => r.value)).toEqual([2, 3]);
    expect(tableRows([{ channel: "a", samples: a }], [0, 20], { limit: 0 }).rows).toEqual([]);
  });
});

describe("formatting", () => {
  it("prints 7 significant digits without trailing zeros", () => {
    expect(formatValue(-9.81234567)).toBe("-9.812346");
    expect(formatValue(0.10000000149011612)).toBe("0.1");
    expect(formatValue(NaN)).toBe("NaN");
  });

  it("prints a time of day with milliseconds", () => {
    const t = new Date(2026, 10, 24, 9, 5, 7, 250).getTime() / 1000;
    expect(clockTime(t)).toBe("09:05:07.250");
  });
});
