/**
 * The workbench of one project: top bar, palette, canvas, inspector and the
 * dock of panels. Loads the project's head revision, keeps the live plan
 * running.
 */
import { useEffect, useMemo, useRef, useState } from "react";
import type { Api } from "../api/client";
import type { ModelVersion } from "../api/types";
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
import { ConflictBanner, DraftNotice, RemoteSaveNotice } from "./ConflictBanner";
import { useProjectEvents } from "./useProjectEvents";
import { useDrafts } from "./useDrafts";
import { FirstStep } from "./FirstStep";
import { RunningDroneHint } from "./RunningDroneHint";
import { readDraft, writeDraft } from "./drafts";
import { goTo, type Route } from "./routes";
import { sameValue } from "../core/merge";
import { push } from "../core/history";
import { LinkBanner } from "./LinkBanner";
import { AlertBanner } from "./AlertBanner";

function LivePlan() {
  useLivePlan();
  useProjectEvents();
  return null;
}

interface Props { project: Project; user: User; onLogout: () => void; onProjects: () => void; route?: Route }

/** Puts back unsaved edits this browser kept for the project: on the head, or offered as a merge when the head moved on. */
async function restoreDraft(api: Api, store: EditorStore, user: string, head: ModelVersion): Promise<void> {
  const project = store.getState().project;
  if (!project) return;
  const draft = readDraft(window.localStorage, user, project.id);
  if (!draft) return;
  if (sameValue(draft.model, head.model)) { writeDraft(window.localStorage, user, project.id, null); return; }
  const when = new Date(draft.savedAt).toLocaleString();
  if (draft.baseRevision === head.revision) {
    store.patch((s) => ({ wb: { ...s.wb, history: push(s.wb.history, draft.model) }, draftRestored: `Unsaved edits of revision ${head.revision} restored from this browser (${when}).` }));
    return;
  }
  const base = await api.readModel(project.id, draft.baseRevision).catch(() => null);
  store.patch({
    draftRestored: `Unsaved edits of revision ${draft.baseRevision} found in this browser (${when}); revision ${head.revision} was saved since.`,
    conflict: { base: base?.model ?? head.model, mine: draft.model, theirs: head.model, revision: head.revision, author: head.author, choices: {} },
  });
}

export function Workbench({ project, user, onLogout, onProjects, route }: Props) {
  const { api } = useServices();
  const views = viewsFor(user.roles as Role[]);
  const firstView = route?.view && views.includes(route.view) ? route.view : views[0] ?? "operator";
  const store: EditorStore = useMemo(() => {
    const s = createEditorStore(emptyModel(), firstView);
    s.patch({ userRoles: user.roles as Role[] });
    if (route?.panel) s.patch({ panel: route.panel });
    return s;
  }, [project.id]); // eslint-disable-line react-hooks/exhaustive-deps
  const [state, setState] = useState<"loading" | "ready" | string>("loading");
  // Decided once, when the project opens (no view asked in the address, the user an admin).
  const allRolesWhenEmpty = useRef(!route?.view && views.includes("admin"));

  useEffect(() => {
    let live = true;
    api.readModel(project.id).then(
      async (v) => {
        if (!live) return;
        loadRevision(store, { id: project.id, name: project.name }, v.revision, v.model);
        // An admin starting a model from nothing builds every part of it: the All roles view.
        if (allRolesWhenEmpty.current && v.model.drone.sensors.length === 0) store.dispatch({ type: "setRole", role: "admin" });
        await restoreDraft(api, store, user.username, v).catch(() => undefined);
        if (live) setState("ready");
      },
      (e: Error) => { if (live) setState(e.message); },
    );
    return () => { live = false; };
  }, [api, project, store, user.username]);

  useDrafts(store, user.username, state === "ready");
  // The address follows the view and the panel (deep links: app/routes.ts).
  useEffect(() => {
    const sync = () => { const s = store.getState(); goTo({ project: project.id, view: s.wb.role as Route["view"], panel: s.panel }); };
    sync();
    return store.subscribe(sync);
  }, [store, project.id]);

  if (state === "loading") return <main className="loading" role="status">Loading {project.name}…</main>;
  if (state !== "ready") return <main className="error" role="alert">Cannot open {project.name}: {state} <button onClick={onProjects}>Back</button></main>;

  return (
    <EditorContext.Provider value={store}>
      <ReactFlowProvider>
        <LivePlan />
        <div className="workbench">
          <TopBar user={user} onLogout={onLogout} onProjects={onProjects} />
          <ConflictBanner />
          <RemoteSaveNotice />
          <DraftNotice />
          <LinkBanner />
          <AlertBanner />
          <FirstStep />
          <RunningDroneHint />
          <div className="main">
            <Palette />
            <div className="center">
              {/* Over the canvas, not above it: a refused edit (told on blur) must not move the
                  diagram under a click already under way, or that click is lost. */}
              <Notice />
              <Canvas />
              <Dock user={user.username} />
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
