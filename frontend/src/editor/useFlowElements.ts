/**
 * The xyflow nodes and edges of the current model: core's graph mapping plus
 * markers (diagnostics, plan), selection and read-only state for the role.
 */
import { useMemo } from "react";
import { MarkerType, type Edge } from "@xyflow/react";
import { modelToGraph } from "../core/graph";
import { nodeMarkers } from "../core/markers";
import { canEdit, canEditEdge } from "../core/roles";
import { localDiagnostics } from "../core/diagnostics";
import { diagnosticsFor, planKey } from "../core/planKey";
import { MODD_SCHEMA } from "../core/schema";
import { useEditor, useModel, useRole, useSelection } from "./useEditor";
import type { ElementNode } from "./nodes/types";

export function useDiagnostics() {
  const model = useModel();
  const backend = useEditor((s) => s.plan.result?.diagnostics);
  const answeredFor = useEditor((s) => s.plan.modelKey);
  const key = useMemo(() => planKey(model), [model]);
  const local = useMemo(() => localDiagnostics(model, MODD_SCHEMA), [model]);
  // The backend's are shown only for the model they answer (not a renamed element's old name).
  const fresh = diagnosticsFor(backend, answeredFor, key);
  return useMemo(() => [...local, ...fresh.map((d) => ({ ...d, source: "backend" }))], [local, fresh]);
}

/** Whether the view can pick an edge of `kind`: the link (its settings, read-only or not), or an edge its role owns. */
const pickable = (kind: string, role: Parameters<typeof canEditEdge>[0]): boolean =>
  kind === "link" || ((kind === "publishes" || kind === "subscribes") && canEditEdge(role, kind));

export function useFlowElements(): { nodes: ElementNode[]; edges: Edge[] } {
  const model = useModel();
  const role = useRole();
  const selection = useSelection();
  const plan = useEditor((s) => s.plan.result?.plan ?? null);
  const diagnostics = useDiagnostics();
  const graph = useMemo(() => modelToGraph(model), [model]);
  const markers = useMemo(() => nodeMarkers(model, diagnostics, plan), [model, diagnostics, plan]);
  return useMemo(() => {
    const selected = new Set(selection);
    const nodes: ElementNode[] = graph.nodes.map((n) => ({
      id: n.id,
      type: n.kind,
      position: n.position,
      selected: selected.has(n.id),
      deletable: false,
      data: { kind: n.kind, label: n.label, detail: n.detail, markers: markers.get(n.id), readOnly: !canEdit(role, n.kind) },
    }));
    const edges: Edge[] = graph.edges.map((e) => ({
      id: e.id,
      source: e.source,
      target: e.target,
      selected: selected.has(e.id),
      // Picked by the canvas's own click and key handlers (editor/Canvas.tsx), never by
      // xyflow's edge selection; still focusable, so Tab reaches them.
      selectable: false,
      focusable: pickable(e.kind, role),
      deletable: false,
      animated: e.kind === "link",
      label: e.kind === "link" ? "link" : undefined,
      markerEnd: e.kind === "publishes" || e.kind === "subscribes" ? { type: MarkerType.ArrowClosed } : undefined,
      className: `edge-${e.kind}${pickable(e.kind, role) ? " pickable" : ""}`,
      data: { kind: e.kind, pickable: pickable(e.kind, role) },
    }));
    return { nodes, edges };
  }, [graph, markers, selection, role]);
}
