/**
 * Saving: PUT the model on top of the revision it was edited from. A stale
 * base gets 409 with the current revision, kept in the store so the top bar
 * can offer to reload; a 403 names the parts the role may not change.
 */
import { useCallback } from "react";
import { ApiError } from "../api/http";
import { currentModel } from "../core/workbench";
import { loadRevision } from "../editor/store";
import { useEditorStore } from "../editor/useEditor";
import { useServices } from "./services";

export function useSaveModel() {
  const { api } = useServices();
  const store = useEditorStore();

  const save = useCallback(async (message = "") => {
    const s = store.getState();
    if (!s.project) return;
    const model = currentModel(s.wb);
    store.patch({ save: { busy: true, error: null, conflictRevision: null } });
    try {
      const saved = await api.saveModel(s.project.id, model, s.savedRevision, message);
      store.patch({ savedRevision: saved.revision, savedModel: model, save: { busy: false, error: null, conflictRevision: null } });
    } catch (e) {
      const conflict = e instanceof ApiError && e.isConflict ? (e.body.current_revision ?? null) : null;
      store.patch({ save: { busy: false, error: (e as Error).message, conflictRevision: conflict } });
    }
  }, [api, store]);

  const reload = useCallback(async () => {
    const s = store.getState();
    if (!s.project) return;
    const v = await api.readModel(s.project.id);
    loadRevision(store, s.project, v.revision, v.model);
  }, [api, store]);

  return { save, reload };
}
