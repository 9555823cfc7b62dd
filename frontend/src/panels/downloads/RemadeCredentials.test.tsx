// @vitest-environment jsdom
import { act, cleanup, render, screen } from "@testing-library/react";
import { afterEach, describe, expect, it, vi } from "vitest";
import type { Api } from "../../api/client";
import { ServicesContext, type Services } from "../../app/services";
import { RemadeCredentials } from "./RemadeCredentials";

afterEach(cleanup);

async function shown(credentialsRemade: () => Promise<unknown>) {
  const services = { api: { credentialsRemade } as unknown as Api } as unknown as Services;
  await act(async () => { render(<ServicesContext.Provider value={services}><RemadeCredentials /></ServicesContext.Provider>); });
}

describe("RemadeCredentials", () => {
  it("names a re-created credential, when, and what to do", async () => {
    await shown(vi.fn(async () => ({ remade: [{ file: "viewer.cred", at: "2026-12-05T02:10:00Z" }] })));
    const alert = screen.getByRole("alert");
    expect(alert.textContent).toContain("viewer.cred (the scientists' viewer credential (their subscriber stubs name it)) was missing and was made anew with a new secret at 2026-12-05 02:10:00Z");
    expect(alert.textContent).toContain("Copies handed out before no longer work");
  });

  it("says nothing when none was, or the backend cannot tell", async () => {
    await shown(vi.fn(async () => ({ remade: [] })));
    expect(screen.queryByRole("alert")).toBeNull();
    cleanup();
    await shown(vi.fn(async () => { throw new Error("404"); }));
    expect(screen.queryByRole("alert")).toBeNull();
  });
});
