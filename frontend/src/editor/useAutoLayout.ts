/** Lays the diagram out with elkjs (one undo step), then zooms to fit. */
import { useCallback, useState } from "react";
import { useReactFlow } from "@xyflow/react";
import { modelToGraph } from "../core/graph";
import { currentModel } from "../core/workbench";
import { autoLayout } from "./autoLayout";
import { useEditorStore } from "./useEditor";
import { FIT } from "./fit";

export function useAutoLayout(): { run: () => Promise<void>; busy: boolean } {
  const store = useEditorStore();
  const flow = useReactFlow();
  const [busy, setBusy] = useState(false);
  const run = useCallback(async () => {
    setBusy(true);
    try {
      const positions = await autoLayout(modelToGraph(currentModel(store.getState().wb)));
      store.dispatch({ type: "move", positions });
      requestAnimationFrame(() => void flow.fitView(FIT));
    } finally {
      setBusy(false);
    }
  }, [store, flow]);
  return { run, busy };
}
