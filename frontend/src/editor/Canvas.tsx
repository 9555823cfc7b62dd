/**
 * The diagram: xyflow canvas over the model. Positions move locally while
 * dragging and are written to the model's layout on drop (one undo step);
 * connections and selection go through the store (an edge is picked by a
 * click, or by Tab then Enter: the link opens its radio settings in the
 * inspector, a publisher → topic or topic → subscriber edge can be deleted);
 * deletion and clipboard go
 * through the keyboard shortcuts (xyflow's own delete key is off, so the
 * model decides what can be removed).
 */
import { useCallback, useEffect, useRef, useState } from "react";
import {
  Background, Controls, MiniMap, ReactFlow, applyNodeChanges, useStore,
  type Connection, type Edge, type NodeChange, type OnSelectionChangeParams,
} from "@xyflow/react";
import { nodeTypes } from "./nodes/nodeTypes";
import type { ElementNode } from "./nodes/types";
import { useFlowElements } from "./useFlowElements";
import { useEditorStore, useModel, useRole } from "./useEditor";
import { useKeyboardShortcuts } from "./useKeyboardShortcuts";
import { canConnect } from "../core/ops";
import { canEditEdge } from "../core/roles";
import { FAR_ZOOM, FIT, farLabelPx } from "./fit";
import { useRevealNew } from "./useRevealNew";
import { useModelDrop } from "./useModelDrop";

const MINIMAP_COLORS: Record<string, string> = {
  drone: "#0f766e", sensor: "#7c3aed", topic: "#2563eb", publisher: "#b45309", subscriber: "#be185d",
  pubBroker: "#475569", subBroker: "#475569",
};

export function Canvas() {
  const store = useEditorStore();
  const model = useModel();
  const role = useRole();
  const derived = useFlowElements();
  const [nodes, setNodes] = useState<ElementNode[]>(derived.nodes);
  useKeyboardShortcuts();
  const drop = useModelDrop(); // a whole model file dropped on the diagram
  const box = useRef<HTMLDivElement>(null);
  useRevealNew(box);
  // Below FAR_ZOOM: names only, at a legible size (fit.ts); the zoom in steps of 0.02 (rounded down), not each frame.
  const zoom = useStore((s) => Math.floor(s.transform[2] * 50) / 50);
  const far = zoom < FAR_ZOOM;

  useEffect(() => {
    // Keep xyflow's measurements across re-derivations of the nodes.
    setNodes((prev) => {
      const byId = new Map(prev.map((n) => [n.id, n]));
      return derived.nodes.map((n) => ({ ...n, measured: byId.get(n.id)?.measured }));
    });
  }, [derived.nodes]);

  const onNodesChange = useCallback((changes: NodeChange<ElementNode>[]) => {
    setNodes((ns) => applyNodeChanges(changes.filter((c) => c.type !== "remove"), ns));
  }, []);

  // Edges are picked here, not by xyflow's own edge selection (which would need a second
  // copy of the selection kept in step with the store's): a click, or Enter/Space on a
  // focused edge, selects it in the store, and the edges' `selected` is derived from there.
  const pickEdge = useCallback((edge: Edge | undefined) => {
    if (edge && (edge.data as { pickable?: boolean } | undefined)?.pickable) store.dispatch({ type: "select", ids: [edge.id] });
  }, [store]);
  const onEdgeClick = useCallback((_e: React.MouseEvent, edge: Edge) => pickEdge(edge), [pickEdge]);
  const onKeyDown = useCallback((e: React.KeyboardEvent) => {
    if (e.key !== "Enter" && e.key !== " ") return;
    const id = (e.target as Element).closest?.(".react-flow__edge")?.getAttribute("data-id");
    if (!id) return;
    e.preventDefault();
    pickEdge(derived.edges.find((x) => x.id === id));
  }, [derived.edges, pickEdge]);

  const onNodeDragStop = useCallback((_e: unknown, _n: ElementNode, dragged: ElementNode[]) => {
    store.dispatch({ type: "move", positions: Object.fromEntries(dragged.map((n) => [n.id, n.position])) });
  }, [store]);

  // Nodes are selected by xyflow (click, box, modifier keys); an edge only by pickEdge
  // below, one at a time. A node picked drops the edge; with no node the picked edge stays.
  const onSelectionChange = useCallback(({ nodes: ns, edges: es }: OnSelectionChangeParams) => {
    store.dispatch({ type: "select", ids: ns.length ? ns.map((n) => n.id) : es.map((e) => e.id) });
  }, [store]);
  const onPaneClick = useCallback(() => store.dispatch({ type: "select", ids: [] }), [store]);

  const onConnect = useCallback((c: Connection) => {
    if (c.source && c.target) store.dispatch({ type: "connect", source: c.source, target: c.target });
  }, [store]);

  const isValidConnection = useCallback((c: Connection | Edge) => {
    if (!c.source || !c.target) return false;
    const kind = c.source.startsWith("pub:") ? "publishes" : "subscribes";
    return canEditEdge(role, kind) && canConnect(model, c.source, c.target);
  }, [model, role]);

  return (
    <div className={`canvas${far ? " canvas-far" : ""}`} aria-label="Model diagram" ref={box} onDragOver={drop.onDragOver} onDrop={drop.onDrop} onKeyDown={onKeyDown}
      style={far ? ({ "--far-label-px": `${farLabelPx(zoom)}px` } as React.CSSProperties) : undefined}>
      <ReactFlow<ElementNode>
        nodes={nodes}
        edges={derived.edges}
        onEdgeClick={onEdgeClick}
        nodeTypes={nodeTypes}
        onNodesChange={onNodesChange}
        onNodeDragStop={onNodeDragStop}
        onSelectionChange={onSelectionChange}
        onPaneClick={onPaneClick}
        onConnect={onConnect}
        isValidConnection={isValidConnection}
        deleteKeyCode={null}
        fitView
        fitViewOptions={FIT}
        minZoom={0.2}
        proOptions={{ hideAttribution: true }}
      >
        <Background gap={20} size={1} />
        <Controls showInteractive={false} />
        <MiniMap pannable zoomable nodeColor={(n) => MINIMAP_COLORS[n.type ?? ""] ?? "#64748b"} ariaLabel="Minimap" />
      </ReactFlow>
    </div>
  );
}
