/**
 * The .modd text of the model in CodeMirror, two-way with the diagram:
 * - diagram → text: the backend prints the saved revision (export); while the
 *   diagram has unsaved edits the text says so and offers to refresh after saving;
 * - text → diagram: "Apply" parses the text with the backend (validate), shows
 *   syntax and validation errors as markers at line:col, and on success
 *   replaces the model (one undo step, the diagram layout kept).
 */
import { useCallback, useEffect, useRef, useState } from "react";
import { EditorView, basicSetup } from "codemirror";
import { EditorState } from "@codemirror/state";
import { linter, setDiagnostics, type Diagnostic as CmDiagnostic } from "@codemirror/lint";
import { moddLanguage } from "./modeLanguage";
import { offsetOf } from "./positions";
import { useEditor, useEditorStore } from "../../editor/useEditor";
import { isDirty } from "../../editor/store";
import { useServices } from "../../app/services";
import { currentModel } from "../../core/workbench";
import type { Diagnostic } from "../../core/diagnostics";

function toCm(text: string, diags: Diagnostic[]): CmDiagnostic[] {
  return diags.map((d) => {
    const from = d.line ? offsetOf(text, d.line, d.col ?? 1) : 0;
    return { from, to: Math.min(from + 1, text.length), severity: d.severity === "error" ? "error" : "warning", message: d.message };
  });
}

export default function TextPanel() {
  const { api } = useServices();
  const store = useEditorStore();
  const project = useEditor((s) => s.project);
  const revision = useEditor((s) => s.savedRevision);
  const dirty = useEditor(isDirty);
  const host = useRef<HTMLDivElement>(null);
  const view = useRef<EditorView | null>(null);
  const [status, setStatus] = useState<{ kind: "info" | "error" | "ok"; text: string } | null>(null);
  const [loading, setLoading] = useState(false);

  useEffect(() => {
    if (!host.current) return;
    const v = new EditorView({
      parent: host.current,
      state: EditorState.create({ doc: "", extensions: [basicSetup, moddLanguage, linter(null), EditorView.lineWrapping] }),
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
      setStatus({ kind: "info", text: `Text of revision ${store.getState().savedRevision}.` });
    } catch (e) {
      setStatus({ kind: "error", text: (e as Error).message });
    } finally {
      setLoading(false);
    }
  }, [api, project, store]);

  useEffect(() => { void refresh(); }, [refresh, revision]);

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
        {dirty && <span className="muted">The diagram has unsaved edits: save to see them here.</span>}
        {status && <span className={`status-${status.kind}`} role="status">{status.text}</span>}
      </div>
      <div className="cm-host" ref={host} aria-label=".modd text" />
    </div>
  );
}
