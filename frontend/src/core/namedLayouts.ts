/**
 * Named dock layouts, like Foxglove's: saved under a name per user and role
 * (in this browser: the backend keeps no per-user settings), switched to,
 * deleted, and exported to / imported from a JSON file. An imported file is
 * checked field by field and refused with a located error, never applied in
 * part. Pure: storage goes through a Storage-like object.
 *
 * @example
 *   saveNamed(localStorage, "ana", "scientist", "Survey", { panel: "monitor", layout })
 *   listNamed(localStorage, "ana", "scientist", ids) // { Survey: { panel: "monitor", layout } }
 *   parseLayoutFile(text, ids) // { name, layout, panel } or { error: "…" }
 */
import { MAX_BESIDE, sanitize, type DockLayout } from "./dockLayout";
import type { PanelId } from "../editor/store";

/** The `format` an exported layout file carries. */
export const LAYOUT_FORMAT = "modd-dock-layout";
export const LAYOUT_VERSION = 1;
export const MAX_NAME = 60;
/** Named layouts kept per user and role (the oldest are not dropped: saving one more is refused). */
export const MAX_NAMED = 30;
/** Bytes of an imported file read at most. */
export const MAX_FILE_BYTES = 64 * 1024;

/** A named layout: the dock's arrangement and the tab panel it was saved with. */
export interface NamedLayout { panel: PanelId; layout: DockLayout }

interface KeyValue { getItem(key: string): string | null; setItem(key: string, value: string): void }

const key = (user: string, role: string) => `modd.layouts.${user}.${role}`;

/** Why a layout name cannot be used, or null. */
export function nameProblem(name: string): string | null {
  const n = name.trim();
  if (!n) return "a layout needs a name";
  if (n.length > MAX_NAME) return `a layout name has at most ${MAX_NAME} characters (this one ${n.length})`;
  if ([...n].some((c) => c.charCodeAt(0) < 32 || c.charCodeAt(0) === 127)) return "a layout name holds no control characters";
  return null;
}

/** The user's named layouts for the role, by name (unreadable entries left out). */
export function listNamed(store: KeyValue, user: string, role: string, panels: readonly string[]): Record<string, NamedLayout> {
  let raw: unknown;
  try { raw = JSON.parse(store.getItem(key(user, role)) ?? "{}"); } catch { return {}; }
  const out: Record<string, NamedLayout> = {};
  if (!raw || typeof raw !== "object") return out;
  for (const [name, v] of Object.entries(raw as Record<string, unknown>)) {
    const o = (v && typeof v === "object" ? v : {}) as Record<string, unknown>;
    if (nameProblem(name) || typeof o.panel !== "string" || !panels.includes(o.panel)) continue;
    out[name] = { panel: o.panel as PanelId, layout: sanitize(o.layout, panels) };
  }
  return out;
}

function write(store: KeyValue, user: string, role: string, all: Record<string, NamedLayout>): string | null {
  try { store.setItem(key(user, role), JSON.stringify(all)); return null; } catch { return "this browser does not keep layouts (storage off or full)"; }
}

/** Saves (or replaces) a named layout; the error in words, or null. */
export function saveNamed(store: KeyValue, user: string, role: string, name: string, named: NamedLayout, panels: readonly string[]): string | null {
  const problem = nameProblem(name);
  if (problem) return problem;
  const all = listNamed(store, user, role, panels);
  const n = name.trim();
  if (!(n in all) && Object.keys(all).length >= MAX_NAMED) return `at most ${MAX_NAMED} named layouts per role: delete one first`;
  return write(store, user, role, { ...all, [n]: named });
}

export function deleteNamed(store: KeyValue, user: string, role: string, name: string, panels: readonly string[]): void {
  const all = listNamed(store, user, role, panels);
  delete all[name];
  write(store, user, role, all);
}

/** The file an exported layout is: readable, with its format and version first. */
export function layoutFile(name: string, role: string, named: NamedLayout): string {
  return JSON.stringify({ format: LAYOUT_FORMAT, version: LAYOUT_VERSION, name, role, panel: named.panel, layout: named.layout }, null, 1) + "\n";
}

/** A file name for an exported layout. */
export function layoutFileName(name: string): string {
  return `${name.trim().replace(/[^A-Za-z0-9_.-]+/g, "_") || "layout"}.modd-layout.json`;
}

const isObject = (v: unknown): v is Record<string, unknown> => !!v && typeof v === "object" && !Array.isArray(v);

function checkLayout(l: unknown, panels: readonly string[]): string | null {
  if (!isObject(l)) return "`layout` is not an object";
  if (!Array.isArray(l.beside)) return "`layout.beside` is not a list of panels";
  if (l.beside.length > MAX_BESIDE) return `\`layout.beside\` lists ${l.beside.length} panels (at most ${MAX_BESIDE})`;
  const bad = l.beside.findIndex((p) => typeof p !== "string" || !panels.includes(p));
  if (bad >= 0) return `\`layout.beside[${bad}]\` is ${JSON.stringify(l.beside[bad])}, not a panel (${panels.join(", ")})`;
  if (new Set(l.beside).size !== l.beside.length) return "`layout.beside` names a panel twice";
  if (typeof l.stacked !== "boolean") return "`layout.stacked` is not true or false";
  if (!Array.isArray(l.sizes) || l.sizes.length !== l.beside.length + 1 || !l.sizes.every((x) => typeof x === "number" && Number.isFinite(x) && x > 0))
    return `\`layout.sizes\` is not ${l.beside.length + 1} positive numbers (one per pane)`;
  if (typeof l.height !== "number" || !(l.height >= 160 && l.height <= 900)) return "`layout.height` is not a number of pixels from 160 to 900";
  return null;
}

/** A layout file read back: the named layout, or why it is refused (located by field). */
export function parseLayoutFile(text: string, panels: readonly string[]): { name: string; named: NamedLayout } | { error: string } {
  if (text.length > MAX_FILE_BYTES) return { error: `the file has ${text.length} bytes; a layout file has at most ${MAX_FILE_BYTES}` };
  let v: unknown;
  try { v = JSON.parse(text); } catch (e) { return { error: `not JSON: ${(e as Error).message}` }; }
  if (!isObject(v) || v.format !== LAYOUT_FORMAT) return { error: `not a MoDD layout file: \`format\` is not "${LAYOUT_FORMAT}"` };
  if (v.version !== LAYOUT_VERSION) return { error: `\`version\` is ${JSON.stringify(v.version)}; this workbench reads version ${LAYOUT_VERSION}` };
  const name = typeof v.name === "string" ? v.name.trim() : "";
  const problem = typeof v.name !== "string" ? "`name` is not text" : nameProblem(name);
  if (problem) return { error: `\`name\`: ${problem}` };
  if (typeof v.panel !== "string" || !panels.includes(v.panel)) return { error: `\`panel\` is ${JSON.stringify(v.panel)}, not a panel (${panels.join(", ")})` };
  const bad = checkLayout(v.layout, panels);
  if (bad) return { error: bad };
  return { name, named: { panel: v.panel as PanelId, layout: sanitize(v.layout, panels) } };
}
