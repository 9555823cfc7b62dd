/**
 * Narrow selector hooks on the editor store (xyflow's pattern): a component
 * re-renders only when what it selects changes (Object.is).
 */
import { createContext, useContext, useSyncExternalStore } from "react";
import type { EditorState, EditorStore } from "./store";
import { currentModel } from "../core/workbench";
import type { ModdModel } from "../core/model.gen";

export const EditorContext = createContext<EditorStore | null>(null);

export function useEditorStore(): EditorStore {
  const store = useContext(EditorContext);
  if (!store) throw new Error("useEditorStore: no EditorContext provider above this component");
  return store;
}

export function useEditor<T>(selector: (s: EditorState) => T): T {
  const store = useEditorStore();
  return useSyncExternalStore(store.subscribe, () => selector(store.getState()));
}

export const useModel = (): ModdModel => useEditor((s) => currentModel(s.wb));
export const useRole = () => useEditor((s) => s.wb.role);
export const useSelection = () => useEditor((s) => s.wb.selection);
export const usePlanResult = () => useEditor((s) => s.plan.result);
