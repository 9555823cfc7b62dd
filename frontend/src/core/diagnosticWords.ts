/**
 * Diagnostics in words: each names its element ("subscriber sub_7") instead
 * of only a JSON pointer, and the same message is never listed twice (the
 * editor's own checks and the backend's often agree).
 *
 * @example
 *   diagnosticsInWords(model, [{ severity: "error", message: "topic: required", pointer: "/subscribers/6/topic" }])
 *   // [{ element: "subscriber sub_7", elementId: "sub:sub_7", text: "topic: required", ... }]
 */
import type { Diagnostic } from "./diagnostics";
import type { ModdModel } from "./model.gen";
import { parseId } from "./ids";
import { pointerTarget } from "./query";

export interface WordedDiagnostic {
  severity: Diagnostic["severity"];
  /** The element in words: "subscriber sub_7", "topic gps.lat", "the link", "the drone". */
  element: string;
  elementId: string;
  /** The message, prefixed with the field when the message does not say it. */
  text: string;
  pointer: string | null;
}

const KIND_WORDS: Record<string, string> = {
  drone: "the drone", pubBroker: "the PubBroker", subBroker: "the SubBroker", link: "the link",
  sensor: "sensor", topic: "variable", publisher: "publisher", subscriber: "subscriber",
};

/** "subscriber sub_7" for an element id. */
export function elementWords(id: string): string {
  const p = parseId(id);
  if (!p) return id;
  return p.name ? `${KIND_WORDS[p.kind]} ${p.name}` : KIND_WORDS[p.kind];
}

/** Worded, de-duplicated diagnostics, errors first, in the model's order otherwise. */
export function diagnosticsInWords(model: ModdModel, diags: readonly Diagnostic[]): WordedDiagnostic[] {
  const seen = new Set<string>();
  const out: WordedDiagnostic[] = [];
  for (const d of diags) {
    const t = pointerTarget(model, d.pointer ?? "");
    const field = t.field.filter((f) => !/^\d+$/.test(f)).join(".");
    // Messages like "periodS: required" already name their field.
    const named = !field || d.message.toLowerCase().startsWith(field.toLowerCase()) || d.message.includes(`${field}:`);
    const text = named ? d.message : `${field}: ${d.message}`;
    const element = elementWords(t.id);
    const key = `${d.severity}|${element}|${text.toLowerCase().replace(/\s+/g, " ")}`;
    if (seen.has(key)) continue;
    seen.add(key);
    out.push({ severity: d.severity, element, elementId: t.id, text, pointer: d.pointer ?? null });
  }
  const rank = { error: 0, warning: 1, info: 2 } as const;
  return out.map((d, i) => [d, i] as const).sort((a, b) => rank[a[0].severity] - rank[b[0].severity] || a[1] - b[1]).map(([d]) => d);
}
