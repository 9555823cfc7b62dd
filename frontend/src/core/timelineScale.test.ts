import { describe, expect, it } from "vitest";
import { axisTicks, layoutTicks, niceStep, tickWidth } from "./timelineScale";

describe("schedule strip scale", () => {
  it("keeps 120 ticks apart", () => {
    const xs = Array.from({ length: 120 }, (_, i) => i / 120);
    const w = tickWidth(xs);
    expect(w).toBeLessThan(1000 / 120);
    expect(tickWidth([0, 0.5, 1])).toBe(10);
  });

  it("stacks ticks closer than their width in lanes", () => {
    const xs = [...Array.from({ length: 300 }, (_, i) => i / 300), 0.5 + 1e-4].sort((a, b) => a - b);
    const { width, lanes, lane } = layoutTicks(xs);
    expect(lanes).toBe(2);
    const rects = xs.map((x, i) => [x * (1000 - width), lane[i]]);
    for (let i = 0; i < rects.length; i += 1) for (let j = i + 1; j < rects.length; j += 1) {
      if (rects[i][1] === rects[j][1]) expect(Math.abs(rects[i][0] - rects[j][0])).toBeGreaterThanOrEqual(width);
    }
  });

  it("labels round times", () => {
    expect(niceStep(4.8)).toBe(1);
    expect(axisTicks(0, 2).map((t) => t.label)).toEqual(["0 s", "0.5 s", "1 s", "1.5 s", "2 s"]);
    expect(axisTicks(0.1, 0.3).map((t) => t.label)).toEqual(["0.1 s", "0.15 s", "0.2 s", "0.25 s", "0.3 s"]);
  });
});
