/**
 * Every inspector edit, in every role view, survives the text view: the
 * edited model is printed as .modd and parsed back by the real
 * modd_model (Python, the backend's own code, run once for all edits), and
 * "Apply" of that unchanged text, in every view, is accepted and changes nothing.
 * Needs the project's .venv (scripts/setup.sh): without it the test fails.
 */
import { execFileSync } from "node:child_process";
import { existsSync } from "node:fs";
import { resolve } from "node:path";
import { describe, expect, it } from "vitest";
import type { ModdModel } from "../../core/model.gen";
import { modelToGraph } from "../../core/graph";
import { elementValue } from "../../core/ops";
import { formFor, getPath, type FieldSpec } from "../../core/schemaForm";
import { MODD_SCHEMA } from "../../core/schema";
import { listTopics } from "../../core/query";
import { canEdit, VIEW_ROLES, type ViewRole } from "../../core/roles";
import { currentModel, initialState, reduce } from "../../core/workbench";
import { sameMeaning } from "../../core/canonical";
import { parseField } from "../inspector/FieldInput";

const repo = resolve(__dirname, "../../../..");
const python = resolve(repo, ".venv/bin/python");

/** .modd text → JSON, and every model → .modd text → JSON, by modd_model. */
function viaText(models: unknown[]): Array<ModdModel | string> {
  const script = `
import json, sys
from modd_model import dumps, load_text
out = []
for m in json.load(sys.stdin):
    try:
        r = load_text(dumps(m, "modd"), "edit.modd")
        out.append(r.model if r.model is not None else "; ".join(d.message for d in r.diagnostics))
    except Exception as e:
        out.append(f"print: {e!r}")
print(json.dumps(out))`;
  return JSON.parse(execFileSync(python, ["-c", script], { input: JSON.stringify(models), maxBuffer: 64 << 20 }).toString()) as Array<ModdModel | string>;
}

function demoModel(): ModdModel {
  const script = "import json; from modd_model import load_model; print(json.dumps(load_model('metamodel/examples/demo.modd')))";
  return JSON.parse(execFileSync(python, ["-c", script], { cwd: repo }).toString()) as ModdModel;
}

/** The text a person would type to change this field (what `parseField` then stores). */
function typed(spec: FieldSpec, current: unknown, topics: string[]): string[] | unknown[] {
  switch (spec.input) {
    case "decimal": return ["5", ".5", "0.250", "2"];
    case "integer": return [String(Math.min(Number(spec.maximum ?? 65000), 7100 + (Number(current) || 0) % 100))];
    case "number": return ["2.5"];
    case "name": return [`${String(current ?? "x")}_b`];
    case "text": return [spec.pattern ? "" : "edited in the inspector"].filter(Boolean);
    case "enum": return (spec.options ?? []).filter((o) => o !== current).slice(0, 2);
    case "enumOrText": return ["METER", "mS/cm"];
    case "topic": return topics.filter((t) => t !== current).slice(0, 1);
    case "topics": return [];
    case "choices": return [(spec.options ?? []).slice(-2)];
  }
}

describe("inspector edits round-trip through the text view", () => {
  it("for every role view and every field it may edit", () => {
    if (!existsSync(python)) throw new Error(`${python} is missing: run scripts/setup.sh`);
    const base = demoModel();
    const edits: Array<{ role: ViewRole; what: string; model: ModdModel }> = [];
    for (const role of VIEW_ROLES) {
      for (const node of modelToGraph(base).nodes) {
        if (!canEdit(role, node.kind)) continue;
        const value = elementValue(base, node.id);
        if (!value) continue;
        for (const spec of formFor(MODD_SCHEMA, node.kind)) {
          const current = getPath(value, spec.path);
          // a field of an absent optional object (an endpoint's port without its host) is not an edit on its own
          if (spec.path.length > 1 && getPath(value, spec.path.slice(0, -1)) === undefined) continue;
          for (const text of typed(spec, current, listTopics(base).map((t) => t.name))) {
            const stored = spec.input === "enum" || spec.input === "topic" || spec.input === "choices" ? text : parseField(spec, String(text));
            const s = reduce(initialState(base, role), { type: "setField", id: node.id, path: spec.path, value: stored });
            if (s.notice || currentModel(s) === base) continue; // refused (e.g. a rename reaching another role's part)
            edits.push({ role, what: `${node.id} ${spec.path.join(".")} = ${JSON.stringify(text)}`, model: currentModel(s) });
          }
        }
      }
    }
    expect(edits.length).toBeGreaterThan(60);
    expect(new Set(edits.map((e) => e.role))).toEqual(new Set(["designer", "integrator", "scientist"]));
    const back = viaText(edits.map((e) => e.model));
    const failures: string[] = [];
    edits.forEach((e, i) => {
      const parsed = back[i];
      if (typeof parsed === "string") { failures.push(`${e.role}: ${e.what}: ${parsed}`); return; }
      // The unchanged text is applied in every view (the model is shared: the next person may be another role).
      for (const view of VIEW_ROLES) {
        const applied = reduce(initialState(e.model, view), { type: "replaceModel", model: { ...parsed, layout: e.model.layout } });
        if (applied.notice) failures.push(`${e.role}: ${e.what}: Apply in the ${view} view refused: ${applied.notice}`);
        else if (!sameMeaning(currentModel(applied), e.model)) failures.push(`${e.role}: ${e.what}: the text changed the model`);
      }
    });
    expect(failures).toEqual([]);
  }, 60_000);
});
