// @vitest-environment jsdom
import { afterEach, describe, expect, it } from "vitest";
import { cleanup, fireEvent, render, screen, waitFor } from "@testing-library/react";
import { DatasetMetadataForm } from "./DatasetMetadataForm";
import { ServicesContext, type Services } from "../../app/services";
import { ApiError } from "../../api/http";
import { scenario1 } from "../../core/testing/scenario1";
import type { DatasetMetadata, DatasetMetadataDoc } from "../../api/types";

afterEach(cleanup);

/** The form with a fake backend: what it holds, and every document saved. */
function mount(reject?: { detail: string; key: string }) {
  const saves: Array<{ doc: DatasetMetadataDoc; base: number }> = [];
  let held: DatasetMetadata = { project_id: 1, revision: 0, metadata: {}, author: null, created_at: null, missing: ["creator_name", "license"] };
  const api = {
    readDatasetMetadata: async () => held,
    saveDatasetMetadata: async (_p: number, doc: DatasetMetadataDoc, base: number) => {
      if (reject) throw new ApiError(422, reject.detail, reject);
      saves.push({ doc, base });
      held = { ...held, revision: base + 1, metadata: doc, missing: ["license"] };
      return held;
    },
  } as unknown as Services["api"];
  render(
    <ServicesContext.Provider value={{ api, openStream: () => { throw new Error("no stream"); } }}>
      <DatasetMetadataForm model={scenario1()} project={1} />
    </ServicesContext.Provider>,
  );
  return saves;
}

const type = (label: string, value: string) => fireEvent.change(screen.getByLabelText(label), { target: { value } });

describe("Archives → Dataset metadata", () => {
  it("saves what the scientist filled as the next revision, nothing invented", async () => {
    const saves = mount();
    await screen.findByText(/Not given yet.*creator_name, license/);
    expect((screen.getByLabelText("Creator name") as HTMLInputElement).value).toBe(""); // no default creator
    type("Creator name", "Ana Example");
    type("Naming authority", "org.example.marine");
    type("Instrument accelerometer make", "Bosch");
    fireEvent.click(screen.getByRole("button", { name: "Save metadata" }));
    await screen.findByText("Saved revision 1");
    expect(saves).toEqual([{
      base: 0,
      doc: { creator_name: "Ana Example", naming_authority: "org.example.marine", instruments: { accelerometer: { make: "Bosch" } } },
    }]);
  });

  it("marks a bad field before saving, and the backend's located fault beside its field", async () => {
    const saves = mount();
    await screen.findByText(/Not given yet/);
    type("Naming authority", "modd");
    fireEvent.click(screen.getByRole("button", { name: "Save metadata" }));
    expect(await screen.findByText("Naming authority: not reversed DNS (org.example)")).toBeTruthy();
    expect(screen.getByLabelText("Naming authority").getAttribute("aria-invalid")).toBe("true");
    expect(saves).toEqual([]);
    cleanup();
    mount({ detail: "metadata: instruments.ctd: the model has no sensor 'ctd'", key: "platform.id" });
    await screen.findByText(/Not given yet/);
    type("Platform id", "usv01");
    fireEvent.click(screen.getByRole("button", { name: "Save metadata" }));
    await waitFor(() => expect(screen.getByLabelText("Platform id").getAttribute("aria-invalid")).toBe("true"));
  });
});
