/**
 * The workbench's addresses: `/` the projects, `/projects/<id>` a project,
 * `/projects/<id>/<view>/<panel>` a project in a role view with a panel
 * open. Deep links work after login (the page keeps its URL through it).
 *
 * @example parseRoute("/projects/3/scientist/monitor") // { project: 3, view: "scientist", panel: "monitor" }
 */
import { VIEW_ROLES, type ViewRole } from "../core/roles";
import type { PanelId } from "../editor/store";

export interface Route {
  project: number | null;
  view: ViewRole | null;
  panel: PanelId | null;
}

const PANEL_IDS: readonly PanelId[] = ["plan", "text", "deploy", "monitor", "fleet", "scene3d", "archives", "downloads", "history"];

export function parseRoute(path: string): Route {
  const m = /^\/projects\/(\d{1,9})(?:\/([a-z]+))?(?:\/([a-z0-9]+))?\/?$/.exec(path);
  if (!m) return { project: null, view: null, panel: null };
  const view = ([...VIEW_ROLES, "admin"] as readonly string[]).includes(m[2] ?? "") ? (m[2] as ViewRole) : null;
  const panel = (PANEL_IDS as readonly string[]).includes(m[3] ?? "") ? (m[3] as PanelId) : null;
  return { project: Number(m[1]), view, panel };
}

export function formatRoute(r: Route): string {
  if (r.project === null) return "/";
  if (!r.view) return `/projects/${r.project}`;
  return `/projects/${r.project}/${r.view}${r.panel ? `/${r.panel}` : ""}`;
}

/** Moves the address bar to `r` (push: a new history entry; else replace). */
export function goTo(r: Route, push = false): void {
  const path = formatRoute(r);
  if (window.location.pathname === path) return;
  if (push) window.history.pushState(null, "", path);
  else window.history.replaceState(null, "", path);
}
