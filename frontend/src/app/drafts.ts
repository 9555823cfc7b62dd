/**
 * Unsaved edits kept in this browser (localStorage) until they are saved, so
 * a reload, a crash or a closed tab loses nothing. One draft per user and
 * project: the model and the revision it was edited from.
 *
 * Contract: `writeDraft` is called with the editor's state after changes
 * (debounced by the caller); a clean editor removes the draft. Storage
 * errors (quota, private mode) are ignored: the draft is a safety net.
 */
import type { ModdModel } from "../core/model.gen";

export interface Draft {
  baseRevision: number;
  model: ModdModel;
  savedAt: string;
}

const key = (user: string, project: number) => `modd.draft.${user}.${project}`;

export function readDraft(store: Storage, user: string, project: number): Draft | null {
  try {
    const raw = store.getItem(key(user, project));
    if (!raw) return null;
    const d = JSON.parse(raw) as Draft;
    return typeof d.baseRevision === "number" && d.model && typeof d.model === "object" ? d : null;
  } catch {
    return null;
  }
}

export function writeDraft(store: Storage, user: string, project: number, draft: Draft | null): void {
  try {
    if (draft) store.setItem(key(user, project), JSON.stringify(draft));
    else store.removeItem(key(user, project));
  } catch { /* full or unavailable: nothing to do */ }
}
