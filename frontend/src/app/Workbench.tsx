/**
 * The workbench of one project: top bar, palette, canvas, inspector and the
 * dock of panels. Loads the project's head revision, keeps the live plan
 * running.
 */
import { useEffect, useMemo, useState } from "react";
import { ReactFlowProvider } from "@xyflow/react";
import "@xyflow/react/dist/style.css";
import type { Project, User } from "../api/types";
import { viewsFor, type Role } from "../core/roles";
import { emptyModel } from "../core/templates";
import { createEditorStore, loadRevision, type EditorStore } from "../editor/store";
import { EditorContext } from "../editor/useEditor";
import { Canvas } from "../editor/Canvas";
import { Palette } from "../editor/Palette";
import { InspectorPanel } from "../panels/registry";
import { PanelBoundary } from "../panels/PanelBoundary";
import { useServices } from "./services";
import { useLivePlan } from "./useLivePlan";
import { TopBar } from "./TopBar";
import { Dock } from "./Dock";
import { Notice } from "./Notice";
import { LinkBanner } from "./LinkBanner";

function LivePlan() {
  useLivePlan();
  return null;
}

interface Props { project: Project; user: User; onLogout: () => void; onProjects: () => void }

export function Workbench({ project, user, onLogout, onProjects }: Props) {
  const { api } = useServices();
  const firstView = viewsFor(user.roles as Role[])[0] ?? "operator";
  const store: EditorStore = useMemo(() => createEditorStore(emptyModel(), firstView), [project.id]); // eslint-disable-line react-hooks/exhaustive-deps
  const [state, setState] = useState<"loading" | "ready" | string>("loading");

  useEffect(() => {
    let live = true;
    api.readModel(project.id).then(
      (v) => { if (live) { loadRevision(store, { id: project.id, name: project.name }, v.revision, v.model); setState("ready"); } },
      (e: Error) => { if (live) setState(e.message); },
    );
    return () => { live = false; };
  }, [api, project, store]);

  if (state === "loading") return <main className="loading" role="status">Loading {project.name}…</main>;
  if (state !== "ready") return <main className="error" role="alert">Cannot open {project.name}: {state} <button onClick={onProjects}>Back</button></main>;

  return (
    <EditorContext.Provider value={store}>
      <ReactFlowProvider>
        <LivePlan />
        <div className="workbench">
          <TopBar user={user} onLogout={onLogout} onProjects={onProjects} />
          <Notice />
          <LinkBanner />
          <div className="main">
            <Palette />
            <div className="center">
              <Canvas />
              <Dock />
            </div>
            <aside className="side">
              <PanelBoundary title="Inspector"><InspectorPanel /></PanelBoundary>
            </aside>
          </div>
        </div>
      </ReactFlowProvider>
    </EditorContext.Provider>
  );
}
