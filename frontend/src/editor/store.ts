/**
 * The editor's one store: the core workbench state (model history,
 * selection, role) plus what the server said (project, saved revision, live
 * plan and its diagnostics). Components read it through narrow selector hooks
 * (useEditor) and change it through `dispatch` (model edits, via the core
 * reducer) or `patch` (server results).
 */
import type { ModdModel } from "../core/model.gen";
import { canonicalJson } from "../core/canonical";
import { currentModel, initialState, reduce, type Action, type WorkbenchState } from "../core/workbench";
import type { Role } from "../core/roles";
import type { PlanResult } from "../api/types";
import type { Side } from "../core/merge";
import type { PlanJson } from "../core/plan";

export type PanelId = "plan" | "text" | "deploy" | "monitor" | "map" | "fleet" | "scene3d" | "archives" | "downloads" | "history";

export interface EditorState {
  wb: WorkbenchState;
  project: { id: number; name: string } | null;
  savedRevision: number;
  /** The model as last loaded or saved (same object as a history entry, so `dirty` is a reference test). */
  savedModel: ModdModel | null;
  save: { busy: boolean; error: string | null; conflictRevision: number | null };
  plan: PlanState;
  panel: PanelId;
  /** A save refused because revision `revision` was saved meanwhile: the three models to merge. */
  conflict: MergeState | null;
  /** The newest revision someone saved, as announced over the stream socket. */
  remoteSave: { revision: number; author: string; message: string } | null;
  /** Unsaved edits found in this browser at start and put back (when they were kept). */
  draftRestored: string | null;
  /** The signed-in user's roles (the view is one of them; a whole model is checked against all). */
  userRoles: Role[];
}

export interface MergeState {
  base: ModdModel;
  mine: ModdModel;
  theirs: ModdModel;
  revision: number;
  author: string;
  /** How each conflicting field is resolved so far, by pointer. */
  choices: Record<string, Side>;
}

/**
 * The live plan: the last answer, plus the last valid plan (shown greyed
 * while the model has errors) and the valid plan before it (what the last
 * edit changed, core/planDiff).
 */
export interface PlanState {
  busy: boolean;
  result: PlanResult | null;
  error: string | null;
  lastValid?: PlanJson | null;
  previous?: PlanJson | null;
  /** The planKey of the model `result` answers (core/planKey). */
  modelKey?: string;
  /** The archive ("DRONE/NAME.mcap") the live plan is calibrated by, chosen in the Plan panel. */
  calibrate?: string | null;
}

export interface EditorStore {
  getState(): EditorState;
  dispatch(action: Action): void;
  patch(partial: Partial<EditorState> | ((s: EditorState) => Partial<EditorState>)): void;
  subscribe(listener: () => void): () => void;
}

export function createEditorStore(model: ModdModel, role: Role): EditorStore {
  let state: EditorState = {
    wb: initialState(model, role),
    project: null,
    savedRevision: 0,
    savedModel: model,
    save: { busy: false, error: null, conflictRevision: null },
    plan: { busy: false, result: null, error: null },
    panel: "plan",
    conflict: null,
    remoteSave: null,
    draftRestored: null,
    userRoles: [role],
  };
  const listeners = new Set<() => void>();
  const emit = () => listeners.forEach((l) => l());
  return {
    getState: () => state,
    dispatch(action) {
      const wb = reduce(state.wb, action);
      if (wb !== state.wb) {
        state = { ...state, wb };
        emit();
      }
    },
    patch(partial) {
      const p = typeof partial === "function" ? partial(state) : partial;
      state = { ...state, ...p };
      emit();
    },
    subscribe(l) {
      listeners.add(l);
      return () => listeners.delete(l);
    },
  };
}

/** Loads a saved revision: resets the history and marks it saved. */
export function loadRevision(store: EditorStore, project: { id: number; name: string }, revision: number, model: ModdModel): void {
  store.dispatch({ type: "load", model });
  const s = store.getState();
  store.patch({ project, savedRevision: revision, savedModel: currentModel(s.wb), save: { busy: false, error: null, conflictRevision: null }, conflict: null });
}

/** Per edited model, whether it equals a saved one (compared once per pair, not per render). */
const sameAsSaved = new WeakMap<ModdModel, { saved: ModdModel; same: boolean }>();

/**
 * Are there edits to save? Not only "was anything edited": values set back
 * by hand to what was saved are no edit (the top bar stops saying
 * "unsaved"). Compared in canonical form (core/canonical), as the backend
 * compares revisions.
 */
export const isDirty = (s: EditorState): boolean => {
  const current = currentModel(s.wb);
  if (current === s.savedModel) return false;
  if (!s.savedModel) return true;
  const known = sameAsSaved.get(current);
  if (known?.saved === s.savedModel) return !known.same;
  const same = canonicalJson(current) === canonicalJson(s.savedModel);
  sameAsSaved.set(current, { saved: s.savedModel, same });
  return !same;
};
