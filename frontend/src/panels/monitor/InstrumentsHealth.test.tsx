// @vitest-environment jsdom
import { afterEach, describe, expect, it } from "vitest";
import { cleanup, render, screen, within } from "@testing-library/react";
import { InstrumentsHealth } from "./InstrumentsHealth";
import { toLinkStatus } from "../../dataSources/WebSocketSource";
import type { SubBrokerStatus } from "../../core/contracts.gen";

afterEach(cleanup);

/** The operator's table from a status document as the SubBroker sends it. */
function show(sensors: SubBrokerStatus["sensors"]) {
  const link = toLinkStatus({ link: "up", time_ns: 1_700_000_010_000_000_000, sensors });
  render(<InstrumentsHealth sensors={link.sensors ?? []} />);
  return screen.queryByRole("table", { name: "Instruments' health" });
}

const cells = (table: HTMLElement) =>
  within(table).getAllByRole("row").slice(1).map((r) => within(r).getAllByRole("cell").map((c) => c.textContent));

describe("InstrumentsHealth", () => {
  it("shows per sensor its state, last value time, lines ok and bad, reconnects", () => {
    const table = show({
      sounder: { state: 1, lines_ok: 42, lines_bad: 1, reconnects: 0, values: 42, last_value_ms: Date.UTC(2026, 10, 27, 10, 15, 2) },
      gnss: { state: 1, lines_ok: 5400, lines_bad: 3, reconnects: 2, values: 10800, last_value_ms: Date.UTC(2026, 10, 27, 10, 15, 3, 900) },
    })!;
    expect(within(table).getAllByRole("columnheader").map((h) => h.textContent))
      .toEqual(["Instrument", "State", "Last value", "Lines ok", "Lines bad", "Reconnects"]);
    expect(cells(table)).toEqual([
      ["gnss", "open", "10:15:03 UTC", "5400", "3", "2"],
      ["sounder", "open", "10:15:02 UTC", "42", "1", "0"],
    ]);
    expect(screen.queryByRole("alert")).toBeNull();
    expect(screen.getByText(/Instruments: 2/).textContent).toBe(" · Instruments: 2 (2 open)");
  });

  it("flags a closed, a silent and a garbage-only instrument, with Modbus timeouts and exceptions", () => {
    const table = show({
      ctd: { state: 0, lines_ok: 10, lines_bad: 0, reconnects: 1, last_value_ms: Date.UTC(2026, 10, 27, 9, 0, 0) },
      sonde: { state: 2, lines_ok: 0, lines_bad: 0, reconnects: 0, last_value_ms: 0, timeouts: 12, exceptions: 1 },
      wind: { state: 1, lines_ok: 0, lines_bad: 80, reconnects: 0, last_value_ms: 0, values: 0 },
    })!;
    expect(cells(table)).toEqual([
      ["ctd", "closed", "09:00:00 UTC", "10", "0", "1", "0", "0"],
      ["sonde", "silent", "none yet", "0", "0", "0", "12", "1"],
      ["wind", "open", "none yet", "0", "80", "0", "0", "0"],
    ]);
    // the one-line summary names each flagged instrument and why
    expect(screen.getByText(/Instruments: 3/).textContent).toMatch(/^ · Instruments: 3 \(1 open, 1 silent, 1 closed\)/);
    expect(screen.getByRole("alert").textContent).toBe(
      " · ctd: device closed (unplugged or lost); sonde: silent: no value for 3 periods; "
      + "wind: only bad lines (wrong baud rate or format?)");
  });

  it("says why a GNSS receiver gives nothing: it says it has no fix", () => {
    const table = show({
      gnss: { state: 1, lines_ok: 120, lines_bad: 0, reconnects: 0, last_value_ms: 0, values: 0, no_fix: 80, ignored: 40 },
      rtk: { state: 2, lines_ok: 50, lines_bad: 0, reconnects: 0, last_value_ms: 0, values: 10, no_fix: 6 },
    })!;
    expect(within(table).getAllByRole("columnheader").map((h) => h.textContent).at(-1)).toBe("No fix");
    expect(cells(table).map((r) => r.at(-1))).toEqual(["80", "6"]);
    expect(screen.getByRole("alert").textContent).toBe(
      " · gnss: no fix yet (80 fields refused: the receiver said it had no fix); "
      + "rtk: silent: no value for 3 periods (6 fields refused: the receiver said it had no fix)");
  });

  it("shows nothing when no instrument reports", () => {
    expect(show(undefined)).toBeNull();
    expect(show({})).toBeNull();
  });
});

describe("InstrumentsHealth with what a drone could send", () => {
  it("shows 2^53, 2^63, negative, NaN-escaped and string fields without throwing", () => {
    const table = show({
      a: { state: 1, lines_ok: 2 ** 63, lines_bad: -4, reconnects: 0, last_value_ms: 2 ** 53 },
      b: { state: 1, lines_ok: 1, lines_bad: 0, reconnects: 0, last_value_ms: 2 ** 63 },
      c: { state: 9, lines_ok: 1, lines_bad: 0, reconnects: 0, last_value_ms: -1 },
      d: { state: "1", lines_ok: "NaN", lines_bad: "x", reconnects: null, last_value_ms: "1e400" },
    } as never)!;
    expect(cells(table).map((r) => r[2])).toEqual(["none yet", "none yet", "none yet", "none yet"]);
    expect(cells(table)[0][4]).toBe("0");  // a negative counter is no count
    expect(cells(table)[3][1]).toBe("unknown");
  });
});
