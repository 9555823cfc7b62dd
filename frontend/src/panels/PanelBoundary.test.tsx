// @vitest-environment jsdom
import { afterEach, describe, expect, it, vi } from "vitest";
import { act, cleanup, render, screen } from "@testing-library/react";
import { PanelBoundary } from "./PanelBoundary";

afterEach(() => { cleanup(); vi.useRealTimers(); });

let bad = true;
function Fragile() {
  if (bad) throw new RangeError("Invalid time value");
  return <p>charts</p>;
}

describe("PanelBoundary", () => {
  it("recovers by itself once the data is good again", () => {
    vi.useFakeTimers();
    const quiet = vi.spyOn(console, "error").mockImplementation(() => undefined);
    bad = true;
    render(<PanelBoundary title="Monitor" retryMs={3000}><Fragile /></PanelBoundary>);
    expect(screen.getByRole("alert").textContent).toContain("The Monitor panel failed.");
    act(() => { vi.advanceTimersByTime(3000); });  // still bad: fails again, keeps trying
    expect(screen.getByRole("alert")).toBeTruthy();
    bad = false;
    act(() => { vi.advanceTimersByTime(3000); });
    expect(screen.queryByRole("alert")).toBeNull();
    expect(screen.getByText("charts")).toBeTruthy();
    quiet.mockRestore();
  });
});
