// @vitest-environment jsdom
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import { afterEach, describe, expect, it, vi } from "vitest";
import type { Api } from "../../api/client";
import { ServicesContext, type Services } from "../../app/services";
import { Rehearsal } from "./Rehearsal";

afterEach(cleanup);

async function shown(api: Partial<Api>) {
  const services = { api: api as Api } as unknown as Services;
  await act(async () => { render(<ServicesContext.Provider value={services}><Rehearsal drone="usv" /></ServicesContext.Provider>); });
}

describe("Rehearsal", () => {
  it("cuts and restores the simulated link", async () => {
    const setRehearsal = vi.fn(async (_d: string, cut: boolean) => ({ available: true, cut }));
    await shown({ rehearsal: vi.fn(async () => ({ available: true, cut: false })), setRehearsal });
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: "Cut the link" })); });
    expect(setRehearsal).toHaveBeenCalledWith("usv", true);
    expect(screen.getByTestId("rehearsal-state").textContent).toMatch(/is cut/);
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: "Restore the link" })); });
    expect(setRehearsal).toHaveBeenLastCalledWith("usv", false);
    expect(screen.getByRole("button", { name: "Cut the link" })).toBeTruthy();
  });

  it("is not there for a run that is not simulated, and says a refusal", async () => {
    await shown({ rehearsal: vi.fn(async () => ({ available: false, cut: false })) });
    expect(screen.queryByRole("region", { name: "Rehearse an outage" })).toBeNull();
    cleanup();
    await shown({ rehearsal: vi.fn(async () => ({ available: true, cut: false })), setRehearsal: vi.fn(async () => { throw new Error("this needs the role operator"); }) });
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: "Cut the link" })); });
    expect(screen.getByRole("alert").textContent).toBe("this needs the role operator");
  });
});
