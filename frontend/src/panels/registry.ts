/**
 * The dock's panels, loaded lazily: each is its own chunk, fetched when first
 * shown, and rendered inside a PanelBoundary.
 */
import { lazy, type ComponentType, type LazyExoticComponent } from "react";
import type { PanelId } from "../editor/store";

export interface PanelInfo {
  id: PanelId;
  title: string;
  component: LazyExoticComponent<ComponentType>;
}

export const PANELS: PanelInfo[] = [
  { id: "plan", title: "Plan", component: lazy(() => import("./plan/PlanPanel")) },
  { id: "text", title: "Text", component: lazy(() => import("./text/TextPanel")) },
  { id: "downloads", title: "Downloads", component: lazy(() => import("./downloads/DownloadsPanel")) },
  { id: "deploy", title: "Deploy", component: lazy(() => import("./deploy/DeployPanel")) },
  { id: "monitor", title: "Monitor", component: lazy(() => import("./monitor/MonitorPanel")) },
  { id: "map", title: "Map", component: lazy(() => import("./map/MapPanel")) },
  { id: "fleet", title: "Fleet", component: lazy(() => import("./fleet/FleetPanel")) },
  { id: "scene3d", title: "3D", component: lazy(() => import("./scene3d/ScenePanel")) },
  { id: "archives", title: "Archives", component: lazy(() => import("./archives/ArchivesPanel")) },
  { id: "history", title: "History", component: lazy(() => import("./history/HistoryPanel")) },
];

/**
 * The dock's tabs: the Fleet panel only for a campaign (several drones), or when it is
 * the panel shown; a one-drone project's Map and Monitor already say all it would.
 */
export function panelTabs(campaign: boolean, active: PanelId): PanelInfo[] {
  return PANELS.filter((p) => p.id !== "fleet" || campaign || active === "fleet");
}

export const InspectorPanel = lazy(() => import("./inspector/InspectorPanel"));
