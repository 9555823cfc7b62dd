/**
 * Saving: PUT the model on top of the revision it was edited from. A stale
 * base gets 409: the revision saved meanwhile is read and a three-way merge
 * (core/merge.ts) is offered in the conflict banner; nothing local is
 * dropped until the user says so. A 403 names the parts the role may not change.
 */
import { useCallback } from "react";
import { ApiError } from "../api/http";
import { mergeModels } from "../core/merge";
import { currentModel } from "../core/workbench";
import { loadRevision } from "../editor/store";
import { useEditorStore } from "../editor/useEditor";
import { useServices } from "./services";

export function useSaveModel() {
  const { api } = useServices();
  const store = useEditorStore();

  /** Reads the head (or `revision`) and opens the merge of it with the local edits. */
  const startMerge = useCallback(async (revision?: number) => {
    const s = store.getState();
    if (!s.project || !s.savedModel) return;
    const head = await api.readModel(s.project.id, revision);
    const mine = currentModel(s.wb);
    if (mine === s.savedModel) { // nothing local to keep: just load it
      loadRevision(store, s.project, head.revision, head.model);
      return;
    }
    store.patch({
      save: { busy: false, error: null, conflictRevision: head.revision },
      conflict: { base: s.savedModel, mine, theirs: head.model, revision: head.revision, author: head.author, choices: {} },
    });
  }, [api, store]);

  const save = useCallback(async (message = "") => {
    const s = store.getState();
    if (!s.project) return;
    const model = currentModel(s.wb);
    store.patch({ save: { busy: true, error: null, conflictRevision: null } });
    try {
      const saved = await api.saveModel(s.project.id, model, s.savedRevision, message);
      store.patch({ savedRevision: saved.revision, savedModel: model, save: { busy: false, error: null, conflictRevision: null } });
    } catch (e) {
      if (e instanceof ApiError && e.isConflict) {
        store.patch({ save: { busy: false, error: null, conflictRevision: e.body.current_revision ?? null } });
        await startMerge().catch((err: Error) => store.patch({ save: { busy: false, error: err.message, conflictRevision: null } }));
        return;
      }
      store.patch({ save: { busy: false, error: (e as Error).message, conflictRevision: null } });
    }
  }, [api, store, startMerge]);

  /** Applies the merge as the new local edit on top of the revision saved meanwhile (not saved yet). */
  const applyMerge = useCallback(() => {
    const s = store.getState();
    if (!s.project || !s.conflict) return;
    const c = s.conflict;
    const merged = mergeModels(c.base, c.mine, c.theirs, c.choices).model;
    loadRevision(store, s.project, c.revision, c.theirs);
    store.dispatch({ type: "replaceModel", model: merged });
  }, [store]);

  /** Drops the local edits for the revision saved meanwhile; the caller confirms first. */
  const takeTheirs = useCallback(() => {
    const s = store.getState();
    if (!s.project || !s.conflict) return;
    loadRevision(store, s.project, s.conflict.revision, s.conflict.theirs);
  }, [store]);

  const reload = useCallback(async () => {
    const s = store.getState();
    if (!s.project) return;
    const v = await api.readModel(s.project.id);
    loadRevision(store, s.project, v.revision, v.model);
  }, [api, store]);

  return { save, reload, startMerge, applyMerge, takeTheirs };
}
