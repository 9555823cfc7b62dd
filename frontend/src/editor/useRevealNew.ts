/**
 * New nodes appear in view: when elements are created (palette, paste, quick
 * subscribe) and one lies outside the visible part of the diagram, the view
 * pans to it (the zoom is kept).
 */
import { useEffect, useRef } from "react";
import { useReactFlow } from "@xyflow/react";
import { modelToGraph } from "../core/graph";
import { useModel } from "./useEditor";

const NODE_W = 180;
const NODE_H = 60;

export function useRevealNew(container: React.RefObject<HTMLElement | null>): void {
  const flow = useReactFlow();
  const model = useModel();
  const known = useRef<Set<string> | null>(null);
  useEffect(() => {
    const nodes = modelToGraph(model).nodes;
    const before = known.current;
    known.current = new Set(nodes.map((n) => n.id));
    if (!before) return; // the first model: fitView shows it
    const added = nodes.filter((n) => !before.has(n.id));
    if (added.length === 0 || added.length > 20 || !container.current) return; // a load, not a creation
    const { x, y, zoom } = flow.getViewport();
    const { width, height } = container.current.getBoundingClientRect();
    const visible = (p: { x: number; y: number }) => {
      const sx = p.x * zoom + x;
      const sy = p.y * zoom + y;
      return sx >= 0 && sy >= 0 && sx + NODE_W * zoom <= width - 240 && sy + NODE_H * zoom <= height;
    };
    const hidden = added.find((n) => !visible(n.position));
    if (hidden) void flow.setCenter(hidden.position.x + NODE_W / 2, hidden.position.y + NODE_H / 2, { zoom, duration: 200 });
  }, [model, flow, container]);
}
