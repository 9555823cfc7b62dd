/** Removing a selection that may hold nodes and edges. */
import type { EditorStore } from "./store";

/** Edge ids look like `publishes:pub:p->topic:s.v`; returns the two ends. */
export function edgeEnds(id: string): { source: string; target: string } | null {
  const m = /^(publishes|subscribes):(.+)->(.+)$/.exec(id);
  return m ? { source: m[2], target: m[3] } : null;
}

export function removeSelection(store: EditorStore): void {
  const selection = store.getState().wb.selection;
  const edges = selection.map(edgeEnds).filter((e): e is { source: string; target: string } => e !== null);
  const nodes = selection.filter((id) => edgeEnds(id) === null && id !== "link");
  for (const e of edges) store.dispatch({ type: "disconnect", ...e });
  if (nodes.length) store.dispatch({ type: "remove", ids: nodes });
  else if (edges.length) store.dispatch({ type: "select", ids: [] });
}
