/**
 * Automatic layout with elkjs (layered, left to right as data flows).
 * Takes the pure graph, returns positions by element id.
 */
import type { Graph } from "../core/graph";
import type { Position } from "../core/model.gen";

export const NODE_WIDTH = 180;
export const NODE_HEIGHT = 64;

type Elk = InstanceType<typeof import("elkjs/lib/elk.bundled.js").default>;
let elk: Elk | null = null;

export async function autoLayout(graph: Graph): Promise<Record<string, Position>> {
  // elkjs is large: loaded on first use, in its own chunk.
  if (!elk) {
    const { default: ELK } = await import("elkjs/lib/elk.bundled.js");
    elk = new ELK();
  }
  const result = await elk.layout({
    id: "root",
    layoutOptions: {
      "elk.algorithm": "layered",
      "elk.direction": "RIGHT",
      "elk.layered.spacing.nodeNodeBetweenLayers": "70",
      "elk.spacing.nodeNode": "24",
      "elk.layered.nodePlacement.strategy": "BRANDES_KOEPF",
    },
    children: graph.nodes.map((n) => ({ id: n.id, width: NODE_WIDTH, height: NODE_HEIGHT })),
    edges: graph.edges.map((e) => ({ id: e.id, sources: [e.source], targets: [e.target] })),
  });
  const out: Record<string, Position> = {};
  for (const c of result.children ?? []) out[c.id] = { x: c.x ?? 0, y: c.y ?? 0 };
  return out;
}
