/**
 * Diagnostics: the backend's validation results ({severity, message, pointer,
 * file, line, col}) and the editor's own instant checks, in one shape, and
 * their placement on diagram elements and inspector fields.
 */
import type { ModdModel } from "./model.gen";
import { pointerOf, pointerTarget } from "./query";
import { formFor, checkField, getPath, type JsonSchema } from "./schemaForm";
import { elementValue } from "./ops";
import { modelToGraph } from "./graph";
import { parseId } from "./ids";
import { campaignDiagnostics } from "./campaignForm";

export type Severity = "error" | "warning" | "info";

export interface Diagnostic {
  severity: Severity;
  message: string;
  /** JSON pointer into the model document, when known. */
  pointer?: string | null;
  file?: string | null;
  /** 1-based line and column in the .modd text, when the diagnostic comes from text. */
  line?: number | null;
  col?: number | null;
  /** Where the located text ends (1-based, end_col exclusive), when the parser knows. */
  end_line?: number | null;
  end_col?: number | null;
  /** Where it comes from: "local" (editor checks), "backend", "plan". */
  source?: string;
}

export interface PlacedDiagnostic extends Diagnostic {
  elementId: string;
  field: string[];
}

/** Places diagnostics on elements (by pointer; those without one go to the drone). */
export function placeDiagnostics(model: ModdModel, diags: readonly Diagnostic[]): PlacedDiagnostic[] {
  return diags.map((d) => {
    const t = pointerTarget(model, d.pointer ?? "");
    return { ...d, elementId: t.id, field: t.field };
  });
}

/** Diagnostics grouped by element id; errors first. */
export function byElement(placed: readonly PlacedDiagnostic[]): Map<string, PlacedDiagnostic[]> {
  const map = new Map<string, PlacedDiagnostic[]>();
  const rank = { error: 0, warning: 1, info: 2 } as const;
  for (const d of [...placed].sort((a, b) => rank[a.severity] - rank[b.severity])) {
    const list = map.get(d.elementId) ?? [];
    list.push(d);
    map.set(d.elementId, list);
  }
  return map;
}

/**
 * The editor's instant checks, run on every edit without the backend: each
 * field against the schema, plus the reference checks a diagram makes
 * visible (a subscriber without a topic, a topic nobody publishes).
 * The backend's validation stays the authority; these only give feedback
 * while typing.
 */
export function localDiagnostics(model: ModdModel, schema: JsonSchema): Diagnostic[] {
  const out: Diagnostic[] = [];
  for (const node of modelToGraph(model).nodes) {
    const base = pointerOf(model, node.id);
    const value = elementValue(model, node.id);
    if (!base || !value) continue;
    for (const spec of formFor(schema, node.kind)) {
      const message = checkField(spec, getPath(value, spec.path));
      if (message) {
        out.push({ severity: "error", message: `${spec.label}: ${message}`, pointer: `${base}/${spec.path.join("/")}`, source: "local" });
      }
    }
  }
  out.push(...campaignDiagnostics(model, schema));
  const published = new Set(model.publishers.flatMap((p) => p.topics));
  model.subscribers.forEach((s, i) => {
    if (s.topic && !published.has(s.topic)) {
      out.push({ severity: "warning", message: `no publisher publishes ${s.topic}`, pointer: `/subscribers/${i}/topic`, source: "local" });
    }
  });
  return out;
}

/** Element ids that carry an error, for node markers. */
export function erroneousElements(placed: readonly PlacedDiagnostic[]): Set<string> {
  return new Set(placed.filter((d) => d.severity === "error" && parseId(d.elementId)).map((d) => d.elementId));
}
