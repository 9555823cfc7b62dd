/**
 * Three-way merge of two edits of one model: `base` is the revision both
 * started from, `mine` the local edit, `theirs` the revision saved meanwhile.
 *
 * Contract: the merge goes element by element (arrays of named elements are
 * matched by name, like core/diff.ts) and field by field inside an element;
 * a list where one side has two elements of one name is one conflict as a
 * whole (nothing is dropped).
 * A field changed on one side only takes that side; changed alike on both,
 * either. Changed differently on both sides — or an element removed on one
 * side and changed on the other — is a `Conflict`: the merged model takes
 * the side `choices[pointer]` names, and `theirs` until a choice is made (so
 * the result is always a whole model, and nothing of mine is dropped unless
 * a conflict is resolved to theirs). Layout conflicts are not asked about:
 * the local positions win (presentation only).
 *
 * @example
 *   const r = mergeModels(base, mine, theirs);
 *   r.conflicts // [{ pointer: "/subscribers/sub_1/periodS", base: "2.0", mine: "1.0", theirs: "5.0" }]
 *   mergeModels(base, mine, theirs, { "/subscribers/sub_1/periodS": "mine" }).model
 */
import type { ModdModel } from "./model.gen";

export interface Conflict {
  /** JSON pointer with named elements by name (as core/diff.ts). */
  pointer: string;
  base: unknown;
  mine: unknown;
  theirs: unknown;
}

export type Side = "mine" | "theirs";

export interface MergeResult {
  model: ModdModel;
  conflicts: Conflict[];
  /** Pointers where my edit was kept on top of theirs (for the banner's summary). */
  kept: string[];
}

type Named = { name: string };
const MISSING = undefined;

function isNamedList(v: unknown): v is Named[] {
  return Array.isArray(v) && v.every((x) => x !== null && typeof x === "object" && typeof (x as Named).name === "string");
}

/** No two elements share a name (a model being edited may hold two for a while). */
function uniqueNames(v: Named[]): boolean {
  return new Set(v.map((x) => x.name)).size === v.length;
}

function isObject(v: unknown): v is Record<string, unknown> {
  return v !== null && typeof v === "object" && !Array.isArray(v);
}

/** Semantic equality of JSON values: key order does not matter. */
export function sameValue(a: unknown, b: unknown): boolean {
  if (a === b) return true;
  if (Array.isArray(a) && Array.isArray(b)) return a.length === b.length && a.every((x, i) => sameValue(x, b[i]));
  if (isObject(a) && isObject(b)) {
    const ka = Object.keys(a).filter((k) => a[k] !== undefined);
    const kb = Object.keys(b).filter((k) => b[k] !== undefined);
    return ka.length === kb.length && ka.every((k) => sameValue(a[k], b[k]));
  }
  return false;
}

interface Ctx {
  choices: Readonly<Record<string, Side>>;
  conflicts: Conflict[];
  kept: string[];
}

function conflict(ctx: Ctx, pointer: string, base: unknown, mine: unknown, theirs: unknown): unknown {
  if (pointer.startsWith("/layout")) return mine; // positions: mine, never asked
  ctx.conflicts.push({ pointer, base, mine, theirs });
  return ctx.choices[pointer] === "mine" ? mine : theirs;
}

function merge(base: unknown, mine: unknown, theirs: unknown, pointer: string, ctx: Ctx): unknown {
  if (sameValue(mine, theirs)) return theirs;
  if (sameValue(base, mine)) return theirs;
  if (sameValue(base, theirs)) { ctx.kept.push(pointer); return mine; }
  // Both sides changed it, differently.
  if (mine === MISSING || theirs === MISSING || base === MISSING) {
    // Removed on one side and changed on the other, or added on both with different content.
    if (base === MISSING && isObject(mine) && isObject(theirs)) return mergeObjects({}, mine, theirs, pointer, ctx);
    return conflict(ctx, pointer, base, mine, theirs);
  }
  if (isNamedList(base) && isNamedList(mine) && isNamedList(theirs)
    && uniqueNames(base) && uniqueNames(mine) && uniqueNames(theirs)) return mergeNamed(base, mine, theirs, pointer, ctx);
  // Two elements of one name on a side cannot be matched by name: the whole
  // list is one conflict below (matching would silently drop one of them).
  if (isObject(base) && isObject(mine) && isObject(theirs)) return mergeObjects(base, mine, theirs, pointer, ctx);
  if (Array.isArray(base) && Array.isArray(mine) && Array.isArray(theirs) && mine.every((x) => typeof x === "string")
    && theirs.every((x) => typeof x === "string") && base.every((x) => typeof x === "string")) {
    return mergeStringSets(base as string[], mine as string[], theirs as string[]);
  }
  return conflict(ctx, pointer, base, mine, theirs);
}

function mergeObjects(base: Record<string, unknown>, mine: Record<string, unknown>, theirs: Record<string, unknown>,
  pointer: string, ctx: Ctx): Record<string, unknown> {
  const out: Record<string, unknown> = {};
  const keys = [...new Set([...Object.keys(theirs), ...Object.keys(mine), ...Object.keys(base)])];
  for (const k of keys) {
    const v = merge(base[k], mine[k], theirs[k], `${pointer}/${k}`, ctx);
    if (v !== MISSING) out[k] = v;
  }
  return out;
}

/** Elements matched by name; theirs' order, then what only I added. */
function mergeNamed(base: Named[], mine: Named[], theirs: Named[], pointer: string, ctx: Ctx): Named[] {
  const b = new Map(base.map((x) => [x.name, x]));
  const m = new Map(mine.map((x) => [x.name, x]));
  const t = new Map(theirs.map((x) => [x.name, x]));
  const names = [...new Set([...theirs.map((x) => x.name), ...mine.map((x) => x.name), ...base.map((x) => x.name)])];
  const out: Named[] = [];
  for (const name of names) {
    const v = merge(b.get(name), m.get(name), t.get(name), `${pointer}/${name}`, ctx);
    if (v !== MISSING) out.push(v as Named);
  }
  return out;
}

/** Lists of names (a publisher's topics): additions and removals of both sides. */
function mergeStringSets(base: string[], mine: string[], theirs: string[]): string[] {
  const removed = new Set([...base.filter((x) => !mine.includes(x)), ...base.filter((x) => !theirs.includes(x))]);
  const out = theirs.filter((x) => !removed.has(x));
  for (const x of mine) if (!out.includes(x) && !removed.has(x)) out.push(x);
  return out;
}

export function mergeModels(base: ModdModel, mine: ModdModel, theirs: ModdModel,
  choices: Readonly<Record<string, Side>> = {}): MergeResult {
  const ctx: Ctx = { choices, conflicts: [], kept: [] };
  const model = merge(base, mine, theirs, "", ctx) as ModdModel;
  return { model, conflicts: ctx.conflicts, kept: ctx.kept };
}

/** A value as the side-by-side view shows it: compact JSON, "(removed)" for none. */
export function showValue(v: unknown): string {
  if (v === undefined) return "(removed)";
  if (typeof v === "string") return v === "" ? '""' : v;
  return JSON.stringify(v);
}
