// @vitest-environment jsdom
import { afterEach, describe, expect, it, vi } from "vitest";
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import { FillGaps } from "./FillGaps";
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
    const startBackfill = vi.fn(async () => progress({ windows_done: 10, bytes_per_s: 420, seconds_left: 3 }));
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
});
