// @vitest-environment jsdom
import { act, renderHook } from "@testing-library/react";
import type { ReactNode } from "react";
import { describe, expect, it } from "vitest";
import { createEditorStore } from "./store";
import { EditorContext } from "./useEditor";
import { useDiagnostics } from "./useFlowElements";
import { emptyModel } from "../core/templates";
import { currentModel } from "../core/workbench";
import { planKey } from "../core/planKey";

describe("useDiagnostics", () => {
  it("drops the backend's warning about var_1 once var_1 is renamed (until the next plan answers)", () => {
    const store = createEditorStore(emptyModel(), "integrator");
    store.dispatch({ type: "addSensor" });
    const warned = { severity: "warning" as const, pointer: "/drone/sensors/0/variables/0",
      message: "no publisher publishes sensor_1.var_1; it will not be archived" };
    store.patch({ plan: { busy: false, error: null, modelKey: planKey(currentModel(store.getState().wb)),
      result: { ok: true, plan: null, diagnostics: [warned], elapsed_ms: 5 } } });
    const wrapper = ({ children }: { children: ReactNode }) => <EditorContext.Provider value={store}>{children}</EditorContext.Provider>;
    const { result } = renderHook(() => useDiagnostics(), { wrapper });
    expect(result.current.map((d) => d.message)).toContain(warned.message);
    act(() => store.dispatch({ type: "setField", id: "topic:sensor_1.var_1", path: ["name"], value: "accel_x" }));
    expect(result.current.map((d) => d.message).join("\n")).not.toMatch(/var_1/);
  });
});
