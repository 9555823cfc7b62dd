import { describe, expect, it } from "vitest";
import { axisTicks, niceStep, tickWidth } from "./timelineScale";

describe("schedule strip scale", () => {
  it("keeps 120 ticks apart", () => {
    const xs = Array.from({ length: 120 }, (_, i) => i / 120);
    const w = tickWidth(xs);
    expect(w).toBeLessThan(1000 / 120);
    expect(tickWidth([0, 0.5, 1])).toBe(10);
  });

  it("labels round times", () => {
    expect(niceStep(4.8)).toBe(1);
    expect(axisTicks(0, 2).map((t) => t.label)).toEqual(["0 s", "0.5 s", "1 s", "1.5 s", "2 s"]);
    expect(axisTicks(0.1, 0.3).map((t) => t.label)).toEqual(["0.1 s", "0.15 s", "0.2 s", "0.25 s", "0.3 s"]);
  });
});
