import { afterEach, describe, expect, it, vi } from "vitest";
import { PlaybackSource, archiveSamples } from "./PlaybackSource";

afterEach(() => { vi.useRealTimers(); });

const series = { a: [1, 2, 3, 4, 5].map((t) => ({ t, value: t * 10 })), b: [{ t: 2.5, value: 1 }] };

describe("PlaybackSource", () => {
  it("shows what was recorded up to the cursor; seek moves it", () => {
    const p = new PlaybackSource(series);
    expect([p.start, p.end]).toEqual([1, 5]);
    expect(p.history("a").map((s) => s.t)).toEqual([1]);
    p.seek(3);
    expect(p.history("a").map((s) => s.value)).toEqual([10, 20, 30]);
    expect(p.history("b")).toHaveLength(1);
    p.seek(0);
    expect(p.history("b")).toHaveLength(0);
  });

  it("plays at a rate, delivers revealed batches, pauses, stops at the end", () => {
    vi.useFakeTimers();
    const p = new PlaybackSource(series, 100);
    const got: number[] = [];
    p.subscribe("a", (batch) => got.push(...batch.map((s) => s.t)));
    p.play(10); // 1 s of recording per 100 ms tick
    vi.advanceTimersByTime(200);
    expect(p.cursor).toBeCloseTo(3);
    expect(got).toEqual([2, 3]);
    p.pause();
    vi.advanceTimersByTime(500);
    expect(p.cursor).toBeCloseTo(3);
    p.play();
    vi.advanceTimersByTime(1000);
    expect(p.cursor).toBe(5);
    expect(p.playing).toBe(false);
    expect(got).toEqual([2, 3, 4, 5]);
  });

  it("reads archive points in seconds, numbers only", () => {
    expect(archiveSamples([[2e9, 1.5], [1e9, true], [3e9, "x"]])).toEqual([{ t: 1, value: 1 }, { t: 2, value: 1.5 }]);
  });
});
