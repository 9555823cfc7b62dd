/**
 * Structural difference between two models (e.g. deployed vs edited), as a
 * list of JSON-pointer changes. Arrays of named elements are matched by name,
 * so reordering is not a change and a rename shows as remove + add.
 * The layout is ignored: it does not change what is deployed.
 *
 * @example diffModels(a, b) // [{ op: "replace", pointer: "/subscribers/sub_1/periodS", before: "2.0", after: "1.0" }]
 */
export interface Change {
  op: "add" | "remove" | "replace";
  /** Pointer with array elements named by their `name` when they have one. */
  pointer: string;
  before?: unknown;
  after?: unknown;
}

const IGNORED = new Set(["/layout"]);

function isNamedList(v: unknown): v is Array<{ name: string }> {
  return Array.isArray(v) && v.every((x) => x !== null && typeof x === "object" && typeof (x as { name?: unknown }).name === "string");
}

function walk(a: unknown, b: unknown, pointer: string, out: Change[]): void {
  if (IGNORED.has(pointer)) return;
  if (a === b) return;
  if (a === undefined) { out.push({ op: "add", pointer, after: b }); return; }
  if (b === undefined) { out.push({ op: "remove", pointer, before: a }); return; }
  if (isNamedList(a) && isNamedList(b)) {
    const am = new Map(a.map((x) => [x.name, x]));
    const bm = new Map(b.map((x) => [x.name, x]));
    for (const [name, x] of am) walk(x, bm.get(name), `${pointer}/${name}`, out);
    for (const [name, x] of bm) if (!am.has(name)) out.push({ op: "add", pointer: `${pointer}/${name}`, after: x });
    return;
  }
  if (Array.isArray(a) && Array.isArray(b)) {
    if (JSON.stringify(a) !== JSON.stringify(b)) out.push({ op: "replace", pointer, before: a, after: b });
    return;
  }
  if (a !== null && b !== null && typeof a === "object" && typeof b === "object") {
    const keys = new Set([...Object.keys(a), ...Object.keys(b)]);
    for (const k of keys) walk((a as Record<string, unknown>)[k], (b as Record<string, unknown>)[k], `${pointer}/${k}`, out);
    return;
  }
  out.push({ op: "replace", pointer, before: a, after: b });
}

export function diffModels(before: unknown, after: unknown): Change[] {
  const out: Change[] = [];
  walk(before, after, "", out);
  return out;
}
