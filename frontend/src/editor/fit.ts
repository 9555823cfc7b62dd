/**
 * How the diagram fits the view: a margin all round, and on the right the
 * minimap's width (200 px + its 15 px offset + a gap), so that no node is
 * fitted under the minimap. Below this zoom the nodes show their names only
 * (details collapse; the names stay legible).
 */
import type { FitViewOptions } from "@xyflow/react";

export const FIT: FitViewOptions = { padding: { top: "24px", left: "24px", bottom: "24px", right: "240px" }, duration: 200 };
export const FAR_ZOOM = 0.45;
