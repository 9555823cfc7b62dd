/** Project, role views, save state (with the revision's message, shown in History) and the user. */
import { useState } from "react";
import { VIEW_TITLES, viewsFor, type Role, type ViewRole } from "../core/roles";
import { isDirty } from "../editor/store";
import { useEditor, useEditorStore } from "../editor/useEditor";
import { useSaveModel } from "./useSaveModel";
import type { User } from "../api/types";

export function TopBar({ user, onLogout, onProjects }: { user: User; onLogout: () => void; onProjects: () => void }) {
  const store = useEditorStore();
  const project = useEditor((s) => s.project);
  const role = useEditor((s) => s.wb.role);
  const dirty = useEditor(isDirty);
  const revision = useEditor((s) => s.savedRevision);
  const save = useEditor((s) => s.save);
  const planBusy = useEditor((s) => s.plan.busy);
  const { save: doSave, reload } = useSaveModel();
  const views = viewsFor(user.roles as Role[]);
  const canSave = role !== "operator";
  const [message, setMessage] = useState("");
  const saveNow = async () => {
    await doSave(message.trim());
    if (!store.getState().save.error && !isDirty(store.getState())) setMessage("");
  };

  return (
    <header className="topbar">
      <button className="brand link" onClick={onProjects} title="All projects">MoDD</button>
      <span className="project-name">{project?.name}</span>
      <span className="revision muted">r{revision}{dirty ? " · unsaved" : ""}{planBusy ? " · planning…" : ""}</span>
      <div className="views" role="tablist" aria-label="Role views">
        {views.map((v: ViewRole) => (
          <button key={v} role="tab" aria-selected={role === v} className={role === v ? "active" : ""}
            onClick={() => {
              store.dispatch({ type: "setRole", role: v });
              store.patch({ panel: v === "operator" ? "deploy" : v === "integrator" ? "downloads" : "plan" });
            }}>{VIEW_TITLES[v]}</button>
        ))}
      </div>
      {save.error && (
        <span className="error save-error" role="alert">
          {save.error}
          {save.conflictRevision !== null && <button onClick={() => void reload()}>Load revision {save.conflictRevision}</button>}
        </span>
      )}
      {canSave && (
        <input className="save-message" aria-label="Revision message" placeholder="What changed (optional)" value={message}
          maxLength={500} onChange={(e) => setMessage(e.target.value)}
          onKeyDown={(e) => { if (e.key === "Enter" && dirty && !save.busy) void saveNow(); }} />
      )}
      <button className="primary" disabled={!canSave || !dirty || save.busy} onClick={() => void saveNow()}
        title={canSave ? "Save a new revision" : "The operator view does not edit the model"}>
        {save.busy ? "Saving…" : "Save"}
      </button>
      <span className="user">{user.username}</span>
      <button onClick={onLogout}>Log out</button>
    </header>
  );
}
