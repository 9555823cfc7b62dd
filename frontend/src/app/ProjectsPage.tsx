/** Choose a project, create an empty one, or import a model file (.modd, the original tool's .collector, JSON). */
import { useEffect, useState } from "react";
import { ApiError } from "../api/http";
import type { Project } from "../api/types";
import type { Diagnostic } from "../core/diagnostics";
import { MODEL_FILE_TYPES, modelFile } from "../core/modelFile";
import { emptyModel } from "../core/templates";
import { PROJECT_TEMPLATES } from "./projectTemplates";
import { useServices } from "./services";

/** How often an empty project list asks again (the demo project arrives after the login line). */
export const EMPTY_POLL_MS = 2000;

export function ProjectsPage({ onOpen, user, onLogout, onUsers }: { onOpen: (p: Project) => void; user: string; onLogout: () => void; onUsers?: () => void }) {
  const { api } = useServices();
  const [projects, setProjects] = useState<Project[] | null>(null);
  const [error, setError] = useState<string | null>(null);
  const [name, setName] = useState("");
  const [drone, setDrone] = useState("usv");
  const [template, setTemplate] = useState<string>("empty");
  const [importNote, setImportNote] = useState<string | null>(null);
  const [importErrors, setImportErrors] = useState<Diagnostic[]>([]);

  // The list follows projects that arrive after the page opened (`make run` loads the
  // demo a few seconds after its login line): polled while it is empty, and again
  // whenever the page comes back into view.
  useEffect(() => {
    let live = true;
    const load = () => api.listProjects().then((ps) => { if (live) { setProjects(ps); setError(null); } }, (e: Error) => { if (live) setError(e.message); });
    void load();
    const onVisible = () => { if (document.visibilityState === "visible") void load(); };
    document.addEventListener("visibilitychange", onVisible);
    window.addEventListener("focus", onVisible);
    return () => { live = false; document.removeEventListener("visibilitychange", onVisible); window.removeEventListener("focus", onVisible); };
  }, [api]);
  const empty = projects !== null && projects.length === 0;
  useEffect(() => {
    if (!empty) return;
    const timer = window.setInterval(() => { api.listProjects().then(setProjects, () => {}); }, EMPTY_POLL_MS);
    return () => window.clearInterval(timer);
  }, [api, empty]);

  const create = async (e: React.FormEvent) => {
    e.preventDefault();
    setError(null);
    try {
      const t = PROJECT_TEMPLATES.find((x) => x.id === template);
      onOpen(t?.text ? await api.importProject(name, t.text, "modd") : await api.createProject(name, emptyModel(drone), "empty project"));
    } catch (err) {
      setError((err as Error).message);
    }
  };

  const importFile = async (file: File) => {
    setError(null);
    setImportErrors([]);
    const f = modelFile(file.name, new Uint8Array(await file.arrayBuffer()));
    setImportNote(f.encoding === "utf-8" ? null : `${file.name} is not UTF-8: read as ${f.encoding}.`);
    try {
      onOpen(await api.importProject(f.name, f.text, f.format));
    } catch (err) {
      setError((err as Error).message);
      if (err instanceof ApiError) setImportErrors(err.body.diagnostics ?? []);
    }
  };

  return (
    <main className="projects">
      <header className="projects-head"><h1>MoDD projects</h1><span>{user}</span>{onUsers && <button onClick={onUsers}>Users and roles</button>}<button onClick={onLogout}>Log out</button></header>
      {error && <p className="error" role="alert">{error}</p>}
      {projects === null && !error && <p role="status">Loading projects…</p>}
      {projects && (
        <ul className="project-list" aria-label="Projects">
          {projects.length === 0 && <li className="muted">No project yet.</li>}
          {projects.map((p) => (
            <li key={p.id}>
              <button className="link" onClick={() => onOpen(p)}>{p.name}</button>
              <span className="muted"> revision {p.head_revision} · by {p.created_by}</span>
            </li>
          ))}
        </ul>
      )}
      <form className="new-project" onSubmit={create} aria-label="New project">
        <h2>New project</h2>
        <label>Project name<input value={name} onChange={(e) => setName(e.target.value)} required pattern="[A-Za-z0-9_][A-Za-z0-9_. \-]*" /></label>
        <label>Start from<select value={template} onChange={(e) => setTemplate(e.target.value)}>
          {PROJECT_TEMPLATES.map((t) => <option key={t.id} value={t.id}>{t.title}</option>)}
        </select></label>
        {template === "empty" && <label>Drone name<input value={drone} onChange={(e) => setDrone(e.target.value)} required pattern="[A-Za-z_][A-Za-z0-9_]*" /></label>}
        <button type="submit">Create</button>
      </form>
      <label className="import">Import a .modd, .collector (original MoDD tool) or JSON file
        <input type="file" accept={MODEL_FILE_TYPES} onChange={(e) => { const f = e.target.files?.[0]; if (f) void importFile(f); }} />
      </label>
      {importNote && <p className="muted" role="status">{importNote}</p>}
      {importErrors.length > 0 && (
        <ul className="import-diagnostics" aria-label="Import problems">
          {importErrors.map((d, i) => (
            <li key={i} className={d.severity}>
              {d.line ? `line ${d.line}:${d.col ?? 1}: ` : ""}{d.severity}: {d.message}{d.pointer ? ` [${d.pointer}]` : ""}
            </li>
          ))}
        </ul>
      )}
    </main>
  );
}
