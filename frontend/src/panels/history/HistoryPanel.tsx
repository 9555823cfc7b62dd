/**
 * Revision history of the project: every saved revision with who, when and
 * why; the difference between any two (tick two rows); restore one as a new
 * revision (nothing is rewritten: the head moves forward); redeploy one to
 * the drone (operator view).
 */
import { useState } from "react";
import type { Version } from "../../api/types";
import { diffModels } from "../../core/diff";
import { isDirty, loadRevision } from "../../editor/store";
import { useEditor, useEditorStore } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { LoadState, usePanelData } from "../usePanelData";
import { changeLine } from "./changeLine";
import "../../app/collab.css";

export default function HistoryPanel() {
  const { api } = useServices();
  const store = useEditorStore();
  const project = useEditor((s) => s.project);
  const saved = useEditor((s) => s.savedRevision);
  const role = useEditor((s) => s.wb.role);
  const [picked, setPicked] = useState<number[]>([]);
  const [note, setNote] = useState<string | null>(null);
  const [diff, setDiff] = useState<{ a: number; b: number; lines: string[] } | null>(null);
  const [versions, reload] = usePanelData<Version[]>(project ? () => api.listVersions(project.id) : null, [project?.id, saved]);
  if (!project) return null;

  const pick = (rev: number, on: boolean) => {
    setPicked((p) => (on ? [...p.filter((r) => r !== rev), rev].slice(-2) : p.filter((r) => r !== rev)));
    setDiff(null);
  };
  const compare = async () => {
    const [a, b] = [...picked].sort((x, y) => x - y);
    const [ma, mb] = await Promise.all([api.readModel(project.id, a), api.readModel(project.id, b)]);
    setDiff({ a, b, lines: diffModels(ma.model, mb.model).map((c) => changeLine(c, [mb.model, ma.model])) });
  };
  const restore = async (rev: number) => {
    const s = store.getState();
    const dirty = isDirty(s);
    if (!window.confirm(`Restore revision ${rev} as a new revision on top of r${s.savedRevision}?`
      + (dirty ? " Your unsaved edits stay in the editor; you will be offered to merge them." : ""))) return;
    try {
      const old = await api.readModel(project.id, rev);
      const head = (await api.listVersions(project.id))[0]?.revision ?? 0;
      const v = await api.saveModel(project.id, old.model, head, `restored revision ${rev}`);
      if (!dirty) loadRevision(store, project, v.revision, v.model);
      setNote(`Revision ${rev} restored as revision ${v.revision}.`);
      reload();
    } catch (e) {
      setNote(`Not restored: ${(e as Error).message}`);
    }
  };
  const redeploy = async (rev: number) => {
    if (!window.confirm(`Deploy revision ${rev} to the drone?`)) return;
    try {
      const d = await api.deploy(project.id, rev);
      setNote(d.status === "acked" ? `Revision ${rev} deployed to ${d.drone} (acked).` : `Deploy of revision ${rev}: ${d.status} ${d.error ?? ""}`);
    } catch (e) {
      setNote(`Not deployed: ${(e as Error).message}`);
    }
  };

  return (
    <div className="history-panel">
      <LoadState value={versions} what="revisions" />
      {note && <p role="status">{note}</p>}
      <div className="actions">
        <button disabled={picked.length !== 2} onClick={() => void compare()}>
          {picked.length === 2 ? `Compare r${Math.min(...picked)} → r${Math.max(...picked)}` : "Tick two revisions to compare"}
        </button>
      </div>
      {diff && (
        <div className="diff" aria-label={`Changes from revision ${diff.a} to ${diff.b}`}>
          {diff.lines.length ? diff.lines.map((l, i) => <div key={i}>{l}</div>) : "No change (layout only)."}
        </div>
      )}
      {versions.state === "ready" && (
        <table aria-label="Revisions">
          <thead><tr><th></th><th>Revision</th><th>By</th><th>When</th><th>Message</th><th></th></tr></thead>
          <tbody>
            {versions.data.map((v) => (
              <tr key={v.revision} data-revision={v.revision}>
                <td><input type="checkbox" aria-label={`Pick revision ${v.revision}`} checked={picked.includes(v.revision)}
                  onChange={(e) => pick(v.revision, e.target.checked)} /></td>
                <td>r{v.revision}{v.revision === saved ? " (open)" : ""}{v.valid ? "" : " ✖ invalid"}</td>
                <td>{v.author}</td>
                <td className="muted">{new Date(v.created_at).toLocaleString()}</td>
                <td>{v.message}</td>
                <td>
                  <button disabled={role === "operator"} onClick={() => void restore(v.revision)}
                    title={role === "operator" ? "The operator view does not edit the model" : "Save this revision's model as a new revision"}>Restore</button>
                  {" "}
                  <button disabled={role !== "operator" || !v.valid} onClick={() => void redeploy(v.revision)}
                    title={role !== "operator" ? "Deploy from the Operator view" : v.valid ? "Deploy this revision" : "An invalid revision cannot be deployed"}>Redeploy</button>
                </td>
              </tr>
            ))}
          </tbody>
        </table>
      )}
    </div>
  );
}
