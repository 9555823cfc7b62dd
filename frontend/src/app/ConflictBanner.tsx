/**
 * Two people edited one project: the save was refused because another
 * revision was saved meanwhile. Shows who saved what, merges both edits
 * (core/merge.ts) and, for fields both changed, the two values side by side
 * with a choice per field, named in the model's words (core/changeWords.ts). Dropping the local edits asks first.
 */
import { mergeModels, type Side } from "../core/merge";
import { fieldInWords, valueInWords } from "../core/changeWords";
import "./collab.css";
import { useEditor, useEditorStore } from "../editor/useEditor";
import { isDirty } from "../editor/store";
import { useSaveModel } from "./useSaveModel";

export function ConflictBanner() {
  const store = useEditorStore();
  const conflict = useEditor((s) => s.conflict);
  const edited = useEditor((s) => s.savedRevision);
  const { applyMerge, takeTheirs } = useSaveModel();
  if (!conflict) return null;
  const result = mergeModels(conflict.base, conflict.mine, conflict.theirs, conflict.choices);
  const open = result.conflicts.filter((c) => !conflict.choices[c.pointer]);
  const choose = (pointer: string, side: Side) =>
    store.patch((s) => (s.conflict ? { conflict: { ...s.conflict, choices: { ...s.conflict.choices, [pointer]: side } } } : {}));

  return (
    <section className="conflict-banner" role="alertdialog" aria-label="Edit conflict">
      <p>
        <strong>Revision {conflict.revision} was saved by {conflict.author}</strong> while you edited revision {edited}.
        Your edits are kept: {result.kept.length} of your changes merge cleanly on top of theirs
        {result.conflicts.length ? `; ${result.conflicts.length} field${result.conflicts.length > 1 ? "s" : ""} changed on both sides — choose for each` : ""}.
      </p>
      {result.conflicts.length > 0 && (
        <table className="conflicts">
          <thead><tr><th>Field</th><th>Before</th><th>Yours</th><th>{conflict.author}'s (r{conflict.revision})</th></tr></thead>
          <tbody>
            {result.conflicts.map((c) => (
              <tr key={c.pointer} data-pointer={c.pointer}>
                <td title={c.pointer}>{fieldInWords(c.pointer)}</td>
                <td className="muted">{valueInWords(c.pointer, c.base)}</td>
                <td><label><input type="radio" name={c.pointer} checked={conflict.choices[c.pointer] === "mine"}
                  onChange={() => choose(c.pointer, "mine")} /> {valueInWords(c.pointer, c.mine)}</label></td>
                <td><label><input type="radio" name={c.pointer} checked={conflict.choices[c.pointer] === "theirs"}
                  onChange={() => choose(c.pointer, "theirs")} /> {valueInWords(c.pointer, c.theirs)}</label></td>
              </tr>
            ))}
          </tbody>
        </table>
      )}
      <div className="actions">
        <button className="primary" disabled={open.length > 0} onClick={applyMerge}
          title={open.length ? "Choose a side for every field first" : "Your edits on top of theirs; save when it looks right"}>
          Merge into revision {conflict.revision}
        </button>
        <button onClick={() => {
          if (window.confirm(`Discard your unsaved edits and load revision ${conflict.revision}?`)) takeTheirs();
        }}>Discard mine, load r{conflict.revision}</button>
        <button onClick={() => store.patch({ conflict: null })}>Later</button>
      </div>
    </section>
  );
}

/** "Revision N saved by X": announced live to everyone with the project open. */
export function RemoteSaveNotice() {
  const remote = useEditor((s) => s.remoteSave);
  const saved = useEditor((s) => s.savedRevision);
  const busy = useEditor((s) => s.save.busy);
  const conflict = useEditor((s) => s.conflict);
  const dirty = useEditor(isDirty);
  const { startMerge } = useSaveModel();
  if (!remote || busy || conflict || remote.revision <= saved) return null;
  return (
    <div className="remote-save" role="status">
      Saved by {remote.author}: revision {remote.revision}{remote.message ? ` (“${remote.message}”)` : ""}.
      {" "}
      <button onClick={() => void startMerge(remote.revision)}>
        {dirty ? `Merge r${remote.revision} with my edits` : `Load revision ${remote.revision}`}
      </button>
    </div>
  );
}

/** Unsaved edits put back from this browser's storage at start. */
export function DraftNotice() {
  const store = useEditorStore();
  const note = useEditor((s) => s.draftRestored);
  if (!note) return null;
  return (
    <div className="draft-restored" role="status">
      {note}
      <button aria-label="Dismiss" onClick={() => store.patch({ draftRestored: null })}>×</button>
    </div>
  );
}
