/**
 * What each diagram node shows besides its name: error and warning markers
 * (from local checks and backend diagnostics), infeasibility reasons from the
 * plan, and a plan badge (a topic's buffer size, a subscriber's delay).
 */
import type { ModdModel } from "./model.gen";
import type { Diagnostic } from "./diagnostics";
import { placeDiagnostics } from "./diagnostics";
import { infeasibleElements, type PlanJson } from "./plan";
import { listTopics } from "./query";
import { subscriberId } from "./ids";

export interface NodeMarkers {
  errors: string[];
  warnings: string[];
  infeasible: string[];
  /** Short plan figure shown on the node, e.g. "n = 28" or "delay 0.88 s". */
  badge?: string;
}

const empty = (): NodeMarkers => ({ errors: [], warnings: [], infeasible: [] });

export function nodeMarkers(model: ModdModel, diagnostics: readonly Diagnostic[], plan: PlanJson | null): Map<string, NodeMarkers> {
  const out = new Map<string, NodeMarkers>();
  const get = (id: string) => {
    let m = out.get(id);
    if (!m) { m = empty(); out.set(id, m); }
    return m;
  };
  const seen = new Set<string>();
  for (const d of placeDiagnostics(model, diagnostics)) {
    const key = `${d.elementId}|${d.severity}|${d.message}`;
    if (seen.has(key)) continue;
    seen.add(key);
    const m = get(d.elementId);
    (d.severity === "error" ? m.errors : m.warnings).push(d.message);
  }
  if (plan) {
    for (const [id, reasons] of infeasibleElements(model, plan)) get(id).infeasible.push(...reasons);
    for (const t of listTopics(model)) {
      const n = plan.buffer_sizes[t.name];
      if (n !== undefined) get(t.id).badge = `n = ${n}`;
    }
    for (const [name, delay] of Object.entries(plan.delays)) get(subscriberId(name)).badge = `delay ${delay} s`;
  }
  return out;
}
