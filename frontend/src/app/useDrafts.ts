/**
 * Keeps the editor's unsaved edits in this browser (app/drafts.ts) while it
 * has any, and warns before the page is left with edits not saved.
 */
import { useEffect } from "react";
import { currentModel } from "../core/workbench";
import { isDirty, type EditorStore } from "../editor/store";
import { writeDraft } from "./drafts";

const DELAY_MS = 300;

export function useDrafts(store: EditorStore, user: string, ready: boolean): void {
  useEffect(() => {
    if (!ready) return;
    let timer: ReturnType<typeof setTimeout> | null = null;
    let last = store.getState().wb.history.present;
    let lastSaved = store.getState().savedModel;
    const flush = () => {
      timer = null;
      const s = store.getState();
      if (!s.project) return;
      writeDraft(window.localStorage, user, s.project.id, isDirty(s)
        ? { baseRevision: s.savedRevision, model: currentModel(s.wb), savedAt: new Date().toISOString() }
        : null);
    };
    const stop = store.subscribe(() => {
      const s = store.getState();
      if (s.wb.history.present === last && s.savedModel === lastSaved) return;
      last = s.wb.history.present;
      lastSaved = s.savedModel;
      if (timer) clearTimeout(timer);
      timer = setTimeout(flush, DELAY_MS);
    });
    const leave = (e: BeforeUnloadEvent) => {
      if (timer) { clearTimeout(timer); flush(); }
      if (!isDirty(store.getState())) return;
      e.preventDefault();
      e.returnValue = ""; // older browsers show their own text
    };
    window.addEventListener("beforeunload", leave);
    return () => {
      stop();
      if (timer) { clearTimeout(timer); flush(); }
      window.removeEventListener("beforeunload", leave);
    };
  }, [store, user, ready]);
}
