// @vitest-environment jsdom
import { afterEach, describe, expect, it, vi } from "vitest";
import { act, cleanup, fireEvent, render, screen, within } from "@testing-library/react";
import { ValuesTable } from "./ValuesTable";
import type { ChannelListener, DataSource, Sample } from "../../dataSources/types";

afterEach(cleanup);

/** A source holding `history` for one channel; `push` delivers a batch as the stream would. */
function fakeSource(history: Sample[]) {
  const listeners: ChannelListener[] = [];
  const source = {
    subscribe: (_c: string, l: ChannelListener) => { listeners.push(l); return () => listeners.splice(listeners.indexOf(l), 1); },
    history: () => history,
  } as unknown as DataSource;
  const push = (batch: Sample[]) => { history.push(...batch); listeners.forEach((l) => l(batch)); };
  return { source, push, listeners };
}

const series = [{ channel: "sub_5", label: "usv.accelerometer.accel_z MIN every 0.25 s", unit: "m/s²", periodS: 0.25 }];

describe("ValuesTable", () => {
  it("opens on Show values: one row per window with start, end, value, samples and the backfilled mark", () => {
    const { source } = fakeSource([
      { t: 1000, value: -9.75, windowS: 0.25 },
      { t: 1000.25, value: -9.5, windowS: 0.25, backfilled: true },
      { t: 1000.5, value: 0.10000000149011612, windowS: 0.25, count: 6 },
    ]);
    render(<ValuesTable source={source} series={series} window={{ follow: true, spanS: 60 }} />);
    expect(screen.queryByRole("table")).toBeNull();
    fireEvent.click(screen.getByRole("button", { name: "Show values" }));
    const table = screen.getByRole("table", { name: "Values of sub_5" });
    expect(screen.getByTestId("values-caption").textContent).toMatch(/sub_5: usv\.accelerometer\.accel_z MIN every 0\.25 s .* 3 values/);
    expect(within(table).getAllByRole("columnheader").map((h) => h.textContent))
      .toEqual(["Window start", "Window end", "Value (m/s²)", "Samples", "Backfilled"]);
    const rows = within(table).getAllByRole("row").slice(1);
    expect(rows.map((r) => within(r).getAllByRole("cell").slice(2).map((c) => c.textContent)))
      .toEqual([["-9.75", "—", "live"], ["-9.5", "—", "backfilled"], ["0.1", "6", "live"]]);
    // the exact figures ride along for tools (the e2e oracle reads them)
    expect(rows[1].dataset).toMatchObject({ channel: "sub_5", start: "1000", end: "1000.25", value: "-9.5" });
    expect(rows[2].dataset.value).toBe("0.10000000149011612");
    expect(rows[1].className).toBe("backfilled");
  });

  it("Backfilled only keeps the backfilled rows; a fixed window keeps only its own", () => {
    const { source } = fakeSource([
      { t: 10, value: 1, windowS: 1 }, { t: 11, value: 2, windowS: 1, backfilled: true },
      { t: 12, value: 3, windowS: 1, backfilled: true }, { t: 20, value: 4, windowS: 1 },
    ]);
    render(<ValuesTable source={source} series={series} window={{ follow: false, from: 10.5, to: 19 }} />);
    fireEvent.click(screen.getByRole("button", { name: "Show values" }));
    const values = () => screen.getAllByRole("row").slice(1).map((r) => r.dataset.value);
    expect(values()).toEqual(["2", "3"]);
    fireEvent.click(screen.getByRole("checkbox", { name: "Backfilled only" }));
    expect(values()).toEqual(["2", "3"]);
    expect(screen.getByTestId("values-caption").textContent).toMatch(/2 backfilled values/);
    fireEvent.click(screen.getByRole("button", { name: "Hide values" }));
    expect(screen.queryByRole("table")).toBeNull();
  });

  it("follows new values (at most every 500 ms) and shows only the newest rows of a long window", async () => {
    vi.useFakeTimers();
    const LIMIT = 50;
    const many = Array.from({ length: LIMIT + 20 }, (_, i) => ({ t: 100 + i * 0.1, value: i }));
    const { source, push } = fakeSource(many);
    const { container } = render(<ValuesTable source={source} series={series} window={{ follow: true, spanS: 3600 }} limit={LIMIT} />);
    fireEvent.click(screen.getByRole("button", { name: "Show values" }));
    // role queries over hundreds of rows are slow in jsdom: plain selectors here
    const last = () => [...container.querySelectorAll<HTMLElement>("tbody tr")].at(-1)?.dataset.value;
    expect(container.querySelectorAll("tbody tr").length).toBe(LIMIT);
    expect(screen.getByTestId("values-caption").textContent).toMatch(new RegExp(`the newest ${LIMIT} of ${LIMIT + 20} values`));
    act(() => push([{ t: 1000, value: -1, backfilled: true }]));
    expect(last()).not.toBe("-1");
    await act(async () => { await vi.advanceTimersByTimeAsync(600); });
    expect(last()).toBe("-1");
    vi.useRealTimers();
  }, 20000);
});
