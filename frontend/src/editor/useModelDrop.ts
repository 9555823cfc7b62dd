/**
 * A whole model file (.modd, .json, the original tool's .collector) dropped on
 * the diagram: read as the import reads it (core/modelFile: its notation by
 * name, windows-1252 when it is not UTF-8), checked by the backend, and
 * applied as one undo step when it has no error and the user's roles may
 * change every part it changes; otherwise the notice says why, in the model's
 * words, and nothing changes.
 */
import { useCallback } from "react";
import { useServices } from "../app/services";
import { currentModel } from "../core/workbench";
import { modelFile } from "../core/modelFile";
import { useEditorStore } from "./useEditor";

const MODEL_NAME = /\.(modd|collector|json)$/i;

export function useModelDrop(): { onDragOver: (e: React.DragEvent) => void; onDrop: (e: React.DragEvent) => void } {
  const { api } = useServices();
  const store = useEditorStore();
  const onDragOver = useCallback((e: React.DragEvent) => {
    if ([...e.dataTransfer.items].some((i) => i.kind === "file")) e.preventDefault(); // allows the drop
  }, []);
  const onDrop = useCallback((e: React.DragEvent) => {
    const file = [...e.dataTransfer.files].find((f) => MODEL_NAME.test(f.name));
    if (!file) return;
    e.preventDefault();
    void (async () => {
      const f = modelFile(file.name, new Uint8Array(await file.arrayBuffer()));
      try {
        const r = await api.validate({ text: f.text, format: f.format });
        const errors = r.diagnostics.filter((d) => d.severity === "error");
        if (!r.model || errors.length) {
          const first = errors[0];
          const where = first?.line ? ` (line ${first.line}:${first.col ?? 1}: ${first.message})` : first ? ` (${first.message})` : "";
          store.dispatch({ type: "notify", notice: `${file.name}: not applied, ${errors.length || "an"} error${errors.length === 1 ? "" : "s"}${where}. Open it in the Text panel to see each one.` });
          return;
        }
        const layout = currentModel(store.getState().wb).layout;
        store.dispatch({ type: "replaceModel", model: { ...r.model, layout: r.model.layout ?? layout }, roles: store.getState().userRoles });
      } catch (err) {
        store.dispatch({ type: "notify", notice: `${file.name}: not applied: ${(err as Error).message}` });
      }
    })();
  }, [api, store]);
  return { onDragOver, onDrop };
}
