// @vitest-environment jsdom
import { afterEach, describe, expect, it, vi } from "vitest";
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import { FillGaps, sumProgress } from "./FillGaps";
import { queueTimeLeft } from "./backfillQueue";
import { ServicesContext, type Services } from "../../app/services";
import type { BackfillProgress } from "../../api/types";
import type { BackfillQueue, BackfillQueueJob } from "../../core/contracts.gen";
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

const job = (id: number, state: BackfillQueueJob["state"], send_s: number | null): BackfillQueueJob => ({
  id, state, windows_done: 0, windows_total: 40, runs_left: 1, send_s,
});
const view = (...jobs: BackfillQueueJob[]): BackfillQueue => ({ jobs, more: 0, pace_bps: 120, trip_s: 0.2 });

describe("the time left of a fill, from the SubBroker's view of its queue", () => {
  it("sums our jobs and, of the others, as much as ours, at the measured pace", () => {
    // ours: 1 on the link (4 s left alone) and 2 queued (3 s, 5 s); another owner's: 30 s and 1 s
    const q = view(job(1, "sending", 4), job(7, "queued", 30), job(2, "queued", 3), job(8, "queued", 1), job(3, "queued", 5));
    expect(queueTimeLeft(q, new Set([1, 2, 3]))).toEqual({ seconds: 4 + 3 + 5 + 12 + 1, waiting: null });
    const ours = [1, 2, 3].map((id) => progress({ id, windows_done: 10, seconds: 9, seconds_left: 99 }));
    const done = progress({ id: 4, status: "DONE", windows: 40, windows_done: 40, seconds: 3 });
    expect(sumProgress([...ours, done], q)).toMatchObject({ status: "RUNNING", windows_done: 70, seconds_left: 25, waiting: null });
  });
  it("gives no number while the drone's archive, the link or the pace is awaited, and says so", () => {
    expect(queueTimeLeft(view(job(1, "waiting_archive", 4), job(2, "queued", 3)), new Set([2]))).toEqual({ seconds: null, waiting: "waiting for the drone's archive" });
    expect(queueTimeLeft(view(job(1, "waiting_link", 4)), new Set([1])).waiting).toBe("waiting for the link");
    expect(queueTimeLeft(view(job(1, "asking", 4), job(2, "queued", null)), new Set([1])).waiting).toBe("measuring the pace");
    expect(queueTimeLeft({ ...view(), more: 40 }, new Set([1])).waiting).toBe("queued behind 0+ jobs");
    expect(queueTimeLeft(null, new Set([1]))).toEqual({ seconds: null, waiting: null });
    const p = sumProgress([progress({ id: 1, seconds_left: 3 })], view(job(1, "waiting_archive", 4)))!;
    expect([p.seconds_left, p.waiting]).toEqual([null, "waiting for the drone's archive"]);
  });
  it("without a view: a lone job's own time left, none for many, none once done", () => {
    expect(sumProgress([progress({ seconds_left: 3 })])!.seconds_left).toBe(3);
    expect(sumProgress([progress({ id: 1, seconds_left: 3 }), progress({ id: 2, seconds_left: 5 })])!.seconds_left).toBeNull();
    expect(sumProgress([progress({ status: "DONE", windows_done: 40, seconds: 3, seconds_left: 3 })])!.seconds_left).toBeNull();
  });
});
