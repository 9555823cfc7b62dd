/**
 * How the diagram fits the view: a margin all round, and on the right the
 * minimap's width (200 px + its 15 px offset + a gap), so that no node is
 * fitted under the minimap. Below FAR_ZOOM the nodes show their names only
 * (details collapse), at a size that reads as at least LEGIBLE_PX on screen
 * down to a zoom of 0.25 (on two lines when a name is long): at fit-to-screen a
 * 30-node model is drawn at a zoom of 0.35–0.6, where 12 px text reads as 4–7 px.
 *
 * @example
 *   farLabelPx(0.35) // 31.4: 11 px on screen
 *   farLabelPx(0.75) // 14.7
 *   farLabelPx(0.1)  // 44: at most four letters a line in a node; so far out nothing reads
 */
import type { FitViewOptions } from "@xyflow/react";

export const FIT: FitViewOptions = { padding: { top: "24px", left: "24px", bottom: "24px", right: "240px" }, duration: 200 };
export const FAR_ZOOM = 0.9;
export const LEGIBLE_PX = 11;

/** The names' font size (in diagram units) below FAR_ZOOM. */
export function farLabelPx(zoom: number): number {
  return Math.min(Math.ceil((LEGIBLE_PX / Math.max(zoom, 0.01)) * 10) / 10, 44);
}
