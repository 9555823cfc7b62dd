// @vitest-environment jsdom
import { afterEach, describe, expect, it, vi } from "vitest";
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import { FillGaps, recentPace, sumProgress } from "./FillGaps";
import { ServicesContext, type Services } from "../../app/services";
import type { BackfillProgress } from "../../api/types";
import type { ChannelListener, DataSource } from "../../dataSources/types";

afterEach(cleanup);

const progress = (p: Partial<BackfillProgress>): BackfillProgress => ({
  status: "RUNNING", id: 3, windows: 0, windows_done: 0, windows_total: 40, duplicates: 0, bytes: 0,
  rate_bps: 600, seconds: 0, bytes_per_s: 0, seconds_left: null, ...p,
});

describe("FillGaps", () => {
  it("starts a backfill, follows it to done and counts the backfilled values", async () => {
    vi.useFakeTimers();
    const listeners: ChannelListener[] = [];
    const source = { subscribe: (_c: string, l: ChannelListener) => { listeners.push(l); return () => {}; } } as unknown as DataSource;
    const startBackfill = vi.fn(async () => progress({ windows_done: 10, bytes_per_s: 420, seconds: 1, seconds_left: 3 }));
    const backfillProgress = vi.fn(async () => progress({ status: "DONE", windows: 40, windows_done: 40 }));
    const services = { api: { startBackfill, backfillProgress }, openStream: () => source } as unknown as Services;
    render(<ServicesContext.Provider value={services}><FillGaps drone="usv" source={source} subscribers={["sub_5"]} scope="sub_5" /></ServicesContext.Provider>);
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: "Fill gaps" })); });
    expect(startBackfill).toHaveBeenCalledWith("usv", { subscriber: "sub_5", gaps: true });
    expect(screen.getByTestId("backfill-progress").textContent).toMatch(/10\/40 windows · 420 of 600 B\/s · 3 s left/);
    act(() => { listeners[0]([{ t: 1, value: 2, backfilled: true }, { t: 2, value: 3 }]); });
    await act(async () => { await vi.advanceTimersByTimeAsync(600); });
    expect(backfillProgress).toHaveBeenCalledWith("usv", 3);
    const text = screen.getByTestId("backfill-progress").textContent ?? "";
    expect(text).toMatch(/done: 40 filled, 0 duplicates/);
    expect(text).toMatch(/1 backfilled values received/);
    vi.useRealTimers();
  });

  it("says what a waiting backfill waits for, one job or many", async () => {
    vi.useFakeTimers();
    const source = { subscribe: () => () => {} } as unknown as DataSource;
    const reasons: Record<string, string> = { sub_1: "paced at 600 B/s", sub_2: "queued behind 1 job", sub_3: "queued behind 2 jobs" };
    const startBackfill = vi.fn(async (_d: string, b: { subscriber: string }) =>
      progress({ id: Number(b.subscriber.slice(4)), reason: reasons[b.subscriber] }));
    const backfillProgress = vi.fn(async () => progress({ reason: "waiting for the link" }));
    const services = { api: { startBackfill, backfillProgress }, openStream: () => source } as unknown as Services;
    render(<ServicesContext.Provider value={services}><FillGaps drone="usv" source={source} subscribers={["sub_1", "sub_2", "sub_3"]} scope="drone usv" /></ServicesContext.Provider>);
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: "Fill gaps" })); });
    expect(screen.getByTestId("backfill-reason").textContent).toBe(" · paced at 600 B/s, 2 queued");
    await act(async () => { await vi.advanceTimersByTimeAsync(600); });
    expect(screen.getByTestId("backfill-reason").textContent).toBe(" · waiting for the link");
    vi.useRealTimers();
  });
});

describe("the time left of many backfills", () => {
  it("is the windows left at the pace of all of them, not the most queued job's own guess", () => {
    // 10 jobs started together, served in turn: after 20 s, 9 are done (40 windows each) and
    // the last has done 4 of 40; its own estimate counts its 20 s queued as its pace (180 s left).
    const done = Array.from({ length: 9 }, () => progress({ status: "DONE", windows: 40, windows_done: 40, seconds: 18 }));
    const last = progress({ windows_done: 4, seconds: 20, seconds_left: 180 });
    const p = sumProgress([...done, last])!;
    expect(p.windows_done).toBe(364);
    expect(p.seconds_left).toBeCloseTo((20 / 364) * 36, 5); // ≈ 2 s: 36 windows at 18 windows/s
    expect(sumProgress([progress({ status: "DONE", windows_done: 40, seconds: 3 })])!.seconds_left).toBeNull();
    expect(sumProgress([progress({ seconds: 2 })])!.seconds_left).toBeNull(); // nothing done yet: no guess
  });
});

describe("the time left during a burst", () => {
  it("follows the recent pace: a burst after a long wait ends in seconds, not at the average pace", () => {
    // 20 s waiting for the drone, then 200 windows in 2 s: 200 of 400 done.
    const seen: [number, number][] = [[0.5, 0], [10, 0], [20, 0], [21, 100], [22, 200]];
    const pace = recentPace(seen)!;
    expect(pace).toBeCloseTo(100, 5); // the last 3 s: 200 windows in 2 s
    const p = sumProgress([progress({ windows_done: 200, windows_total: 400, seconds: 22 })], pace)!;
    expect(p.seconds_left).toBeCloseTo(2, 5); // the average pace (200 in 22 s) would say 22 s
    expect(sumProgress([progress({ windows_done: 200, windows_total: 400, seconds: 22 })])!.seconds_left).toBeCloseTo(22, 5);
  });
  it("makes no guess while nothing moves, nor before a second of samples", () => {
    expect(recentPace([[5, 10], [6, 10], [8, 10]])).toBe(0);
    expect(sumProgress([progress({ windows_done: 10, windows_total: 40, seconds: 8 })], 0)!.seconds_left).toBeNull();
    expect(recentPace([[5, 10], [5.4, 12]])).toBeNull();
    expect(recentPace([[5, 10]])).toBeNull();
  });
});
