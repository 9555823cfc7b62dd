/**
 * The .modd text of the model in CodeMirror, two-way with the diagram:
 * - diagram → text: the backend prints the saved revision (export) and, while
 *   the diagram has unsaved edits, the edited model itself (print), so the text
 *   follows the diagram as you draw — until you edit the text yourself: your
 *   text is then never overwritten until you apply it or reload;
 * - text → diagram: "Apply" parses the text with the backend (validate), shows
 *   syntax and validation errors as markers at line:col, and on success
 *   replaces the model (one undo step, the diagram layout kept).
 */
import { useCallback, useEffect, useRef, useState } from "react";
import { EditorView, basicSetup } from "codemirror";
import { EditorState } from "@codemirror/state";
import { linter, setDiagnostics, type Diagnostic as CmDiagnostic } from "@codemirror/lint";
import { moddLanguage } from "./modeLanguage";
import { rangeOf } from "./positions";
import { useEditor, useEditorStore, useModel } from "../../editor/useEditor";
import { isDirty } from "../../editor/store";
import { useServices } from "../../app/services";
import { currentModel } from "../../core/workbench";
import type { Diagnostic } from "../../core/diagnostics";

function toCm(text: string, diags: Diagnostic[]): CmDiagnostic[] {
  return diags.map((d) => {
    const { from, to } = rangeOf(text, d);
    return { from, to, severity: d.severity === "error" ? "error" : "warning", message: d.message };
  });
}

export default function TextPanel() {
  const { api } = useServices();
  const store = useEditorStore();
  const project = useEditor((s) => s.project);
  const revision = useEditor((s) => s.savedRevision);
  const dirty = useEditor(isDirty);
  const model = useModel();
  // True once the user typed in the text: from then on it is theirs, not the diagram's.
  const textEdited = useRef(false);
  const [mine, setMine] = useState(false);
  // The model the text was just applied as: no need to print it back.
  const applied = useRef<ReturnType<typeof currentModel> | null>(null);
  const markEdited = (edited: boolean) => { textEdited.current = edited; setMine(edited); };
  const host = useRef<HTMLDivElement>(null);
  const view = useRef<EditorView | null>(null);
  const [status, setStatus] = useState<{ kind: "info" | "error" | "ok"; text: string } | null>(null);
  const [loading, setLoading] = useState(false);

  useEffect(() => {
    if (!host.current) return;
    const v = new EditorView({
      parent: host.current,
      state: EditorState.create({
        doc: "",
        extensions: [basicSetup, moddLanguage, linter(null), EditorView.lineWrapping,
          EditorView.updateListener.of((u) => {
            if (u.docChanged && u.transactions.some((t) => t.isUserEvent("input") || t.isUserEvent("delete") || t.isUserEvent("move"))) {
              markEdited(true);
            }
          })],
      }),
    });
    view.current = v;
    return () => v.destroy();
  }, []);

  const setText = (text: string) => {
    const v = view.current;
    if (v) v.dispatch({ changes: { from: 0, to: v.state.doc.length, insert: text } });
  };

  const refresh = useCallback(async () => {
    if (!project) return;
    setLoading(true);
    try {
      setText(await api.exportModel(project.id, "modd"));
      markEdited(false);
      setStatus({ kind: "info", text: `Text of revision ${store.getState().savedRevision}.` });
    } catch (e) {
      setStatus({ kind: "error", text: (e as Error).message });
    } finally {
      setLoading(false);
    }
  }, [api, project, store]);

  useEffect(() => { void refresh(); }, [refresh, revision]);

  // Unsaved diagram edits: print the edited model (debounced; the last edit wins).
  // Undoing back to the saved revision shows the saved text again.
  const wasDirty = useRef(false);
  useEffect(() => {
    const undoneToSaved = wasDirty.current && !dirty;
    wasDirty.current = dirty;
    if (textEdited.current || model === applied.current) return;
    if (undoneToSaved) { void refresh(); return; }
    if (!dirty) return;
    const abort = new AbortController();
    const timer = setTimeout(() => {
      api.printModel(model, abort.signal).then((text) => {
        if (textEdited.current) return;
        setText(text);
        setStatus({ kind: "info", text: `Text of the diagram: revision ${store.getState().savedRevision} with unsaved edits.` });
      }, (e: Error) => {
        if (!abort.signal.aborted) setStatus({ kind: "error", text: `Cannot show the edits as text yet: ${e.message}` });
      });
    }, 250);
    return () => { clearTimeout(timer); abort.abort(); };
  }, [api, dirty, model, refresh, store]);

  const apply = async () => {
    const v = view.current;
    if (!v) return;
    const text = v.state.doc.toString();
    setStatus({ kind: "info", text: "Checking…" });
    try {
      const r = await api.validate({ text, format: "modd" });
      v.dispatch(setDiagnostics(v.state, toCm(text, r.diagnostics)));
      const errors = r.diagnostics.filter((d) => d.severity === "error");
      if (!r.model) {
        setStatus({ kind: "error", text: `${errors.length} error(s): not applied. ${errors.map((d) => `${d.line ?? "?"}:${d.col ?? "?"} ${d.message}`).join("; ")}` });
        return;
      }
      const layout = currentModel(store.getState().wb).layout;
      store.dispatch({ type: "replaceModel", model: { ...r.model, layout: r.model.layout ?? layout } });
      applied.current = currentModel(store.getState().wb);
      markEdited(false);
      const notice = store.getState().wb.notice;
      setStatus(notice ? { kind: "error", text: notice } : { kind: errors.length ? "error" : "ok", text: errors.length ? `Applied with ${errors.length} error(s).` : "Applied to the diagram." });
    } catch (e) {
      const body = (e as { body?: { diagnostics?: Diagnostic[] } }).body;
      if (body?.diagnostics) v.dispatch(setDiagnostics(v.state, toCm(text, body.diagnostics)));
      setStatus({ kind: "error", text: (e as Error).message });
    }
  };

  return (
    <div className="panel-body text-panel">
      <div className="text-toolbar">
        <button onClick={() => void apply()}>Apply text to diagram</button>
        <button onClick={() => void refresh()} disabled={loading}>Reload saved text</button>
        {dirty && mine && <span className="muted">Your text differs from the diagram: apply it, or reload to drop it.</span>}
        {status && <span className={`status-${status.kind}`} role="status">{status.text}</span>}
      </div>
      <div className="cm-host" ref={host} aria-label=".modd text" />
    </div>
  );
}
