/**
 * Keyboard shortcuts of the diagram: Ctrl/⌘+Z undo, Ctrl/⌘+Shift+Z or
 * Ctrl/⌘+Y redo, Delete/Backspace remove the selection, Ctrl/⌘+C copy,
 * Ctrl/⌘+V paste, Ctrl/⌘+D duplicate. Ignored while typing in a field or the text editor.
 */
import { useEffect } from "react";
import { useEditorStore } from "./useEditor";
import { removeSelection } from "./selectionActions";

function typing(target: EventTarget | null): boolean {
  const el = target as HTMLElement | null;
  if (!el) return false;
  return el.isContentEditable || ["INPUT", "TEXTAREA", "SELECT"].includes(el.tagName) || Boolean(el.closest?.(".cm-editor"));
}

export function useKeyboardShortcuts(): void {
  const store = useEditorStore();
  useEffect(() => {
    const onKey = (e: KeyboardEvent) => {
      if (typing(e.target)) return;
      const mod = e.ctrlKey || e.metaKey;
      const key = e.key.toLowerCase();
      const selection = store.getState().wb.selection;
      if (mod && key === "z" && !e.shiftKey) store.dispatch({ type: "undo" });
      else if (mod && ((key === "z" && e.shiftKey) || key === "y")) store.dispatch({ type: "redo" });
      else if (mod && key === "c") store.dispatch({ type: "copy", ids: selection });
      else if (mod && key === "v") store.dispatch({ type: "paste" });
      else if (mod && key === "d" && selection.length) store.dispatch({ type: "duplicate", ids: selection });
      else if ((e.key === "Delete" || e.key === "Backspace") && selection.length) removeSelection(store);
      else return;
      e.preventDefault();
    };
    window.addEventListener("keydown", onKey);
    return () => window.removeEventListener("keydown", onKey);
  }, [store]);
}
