// @vitest-environment jsdom
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import { afterEach, describe, expect, it, vi } from "vitest";
import type { Api } from "../../api/client";
import { ServicesContext, type Services } from "../../app/services";
import { PairDrone } from "./PairDrone";

vi.mock("../saveBlob", () => ({ saveBlob: vi.fn() }));
import { saveBlob } from "../saveBlob";

afterEach(() => { cleanup(); vi.mocked(saveBlob).mockClear(); });

const PAIRING = {
  drone: "usv", revision: 3, filename: "usv.modd-pair", bundle: '{"format":"modd-pair"}\n', code: "7KQ2M-0XH4D-RT9AB-C3PZW",
  fingerprint: "SHA256:aa:bb", expires_at: "2026-12-12T05:00:00Z", link_key_file: "/var/lib/modd/pairing/link-keys/usv.key",
};

function shown(makePairing: Api["makePairing"], allowed = true) {
  const services = { api: { makePairing } as unknown as Api } as unknown as Services;
  render(<ServicesContext.Provider value={services}><PairDrone projectId={7} revision={3} allowed={allowed} /></ServicesContext.Provider>);
}

describe("PairDrone", () => {
  it("saves the bundle as its file and shows the code once, until hidden", async () => {
    const make = vi.fn(async () => PAIRING);
    shown(make);
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: /Make the pairing bundle/ })); });
    expect(make).toHaveBeenCalledWith(7, 3);
    expect(vi.mocked(saveBlob).mock.calls[0][1]).toBe("usv.modd-pair");
    expect(screen.getByLabelText("Pairing code").textContent).toBe(PAIRING.code);
    expect(screen.getByTestId("pairing-made").textContent).toContain(PAIRING.link_key_file);
    fireEvent.click(screen.getByRole("button", { name: "Hide" }));
    expect(screen.queryByLabelText("Pairing code")).toBeNull();
  });

  it("says why it failed, and is for the operator only", async () => {
    shown(vi.fn(async () => { throw new Error("this needs the role operator"); }));
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: /Make the pairing bundle/ })); });
    expect(screen.getByRole("alert").textContent).toContain("this needs the role operator");
    expect(saveBlob).not.toHaveBeenCalled();
    cleanup();
    shown(vi.fn(), false);
    expect((screen.getByRole("button", { name: /Make the pairing bundle/ }) as HTMLButtonElement).disabled).toBe(true);
  });
});
