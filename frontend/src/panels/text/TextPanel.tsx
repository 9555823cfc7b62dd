/**
 * The .modd text of the model in CodeMirror, two-way with the diagram:
 * - diagram → text: the backend prints the saved revision (export) and, while
 *   the diagram has unsaved edits, the edited model itself (print), so the text
 *   follows the diagram as you draw — until you edit the text yourself: your
 *   text is then never overwritten until you apply it or reload;
 * - text → diagram: "Apply" parses the text with the backend (validate): a
 *   whole `.modd`, JSON or original `.collector` model pasted or dropped in is
 *   read as what it is. Text with an error is never applied: each error is a
 *   marker at its line:col, and the status only counts them. Valid text
 *   replaces the model (one undo step, the diagram layout kept) when the
 *   user's roles may change every part it changes (an admin: all), else it is
 *   refused with the parts in the model's words and the ways out.
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

/** A JSON model starts with "{"; anything else is read as .modd (the original .collector too). */
export function textFormat(text: string): "json" | "modd" {
  return text.trimStart().startsWith("{") ? "json" : "modd";
}

/** The status of text not applied: how many errors and where (each is a marker in the text). */
export function notAppliedWords(errors: readonly Diagnostic[]): string {
  if (errors.length === 0) return "Not applied: the text does not describe a model.";
  const where = errors.slice(0, 5).map((d) => (d.line ? `line ${d.line}:${d.col ?? 1}` : (d.pointer ?? "?"))).join(", ");
  return `Not applied: ${errors.length} error${errors.length > 1 ? "s" : ""}, marked in the text (${where}${errors.length > 5 ? ", …" : ""}).`;
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
      const r = await api.validate({ text, format: textFormat(text) });
      v.dispatch(setDiagnostics(v.state, toCm(text, r.diagnostics)));
      const errors = r.diagnostics.filter((d) => d.severity === "error");
      if (!r.model || errors.length) {
        setStatus({ kind: "error", text: notAppliedWords(errors) });
        return;
      }
      const before = currentModel(store.getState().wb);
      store.dispatch({ type: "replaceModel", model: { ...r.model, layout: r.model.layout ?? before.layout }, roles: store.getState().userRoles });
      const after = currentModel(store.getState().wb);
      if (after === before) {
        // Said once, here beside the text (not also in the diagram's notice).
        setStatus({ kind: "error", text: store.getState().wb.notice ?? "Not applied." });
        store.dispatch({ type: "dismissNotice" });
        return;
      }
      applied.current = after;
      markEdited(false);
      setStatus({ kind: "ok", text: "Applied to the diagram." });
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
