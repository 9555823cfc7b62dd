// @vitest-environment jsdom
import { act, fireEvent, render, screen } from "@testing-library/react";
import { describe, expect, it, vi } from "vitest";
import type { Api } from "../api/client";
import { createEditorStore } from "../editor/store";
import { EditorContext } from "../editor/useEditor";
import { scenario1 } from "../core/testing/scenario1";
import { ServicesContext, type Services } from "./services";
import { TopBar } from "./TopBar";

describe("TopBar", () => {
  it("saves with the message typed beside Save (History shows it), then clears it", async () => {
    const store = createEditorStore(scenario1(), "scientist");
    store.patch({ project: { id: 3, name: "demo" }, savedRevision: 1 });
    const saveModel = vi.fn(async () => ({ revision: 2 }));
    const services = { api: { saveModel } as unknown as Api, openStream: vi.fn() } as unknown as Services;
    render(
      <ServicesContext.Provider value={services}>
        <EditorContext.Provider value={store}>
          <TopBar user={{ id: 1, username: "ana", roles: ["scientist"] } as never} onLogout={() => {}} onProjects={() => {}} />
        </EditorContext.Provider>
      </ServicesContext.Provider>,
    );
    act(() => { store.dispatch({ type: "setField", id: "sub:sub_1", path: ["periodS"], value: "4.0" }); });
    const box = screen.getByRole("textbox", { name: "Revision message" });
    fireEvent.change(box, { target: { value: "  sub_1 every 4 s  " } });
    await act(async () => { fireEvent.click(screen.getByRole("button", { name: "Save" })); });
    expect(saveModel).toHaveBeenCalledWith(3, expect.anything(), 1, "sub_1 every 4 s");
    expect((box as HTMLInputElement).value).toBe("");
  });
});
