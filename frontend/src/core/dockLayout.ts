/**
 * The dock's arrangement: the tab panel alone or with one or two more panels
 * (map and Plan beside the Monitor, say), side by side or stacked, each pane's
 * share of the room, and the dock's height; remembered per user and role (in
 * this browser) and reset in one click. Pure: reading and writing go through a
 * Storage-like object.
 *
 * @example
 *   saveLayout(localStorage, "ana", "scientist", { beside: ["map"], stacked: false, sizes: [0.5, 0.5], height: 360 })
 *   loadLayout(localStorage, "ana", "scientist", ids).beside // ["map"]
 *   moveDivider([0.5, 0.5], 0, -0.1) // [0.4, 0.6]
 */
import type { PanelId } from "../editor/store";

export interface DockLayout {
  /** The panels shown with the tab panel (at most MAX_BESIDE), in order. */
  beside: PanelId[];
  /** Stacked (one above the other) rather than side by side. */
  stacked: boolean;
  /** Each pane's share of the width (or height when stacked), tab panel first; they sum to 1. */
  sizes: number[];
  /** The dock's height in CSS pixels, 160–900. */
  height: number;
}

export const MAX_BESIDE = 2;
/** The least share a pane keeps when a divider is dragged. */
export const MIN_SHARE = 0.15;
export const DEFAULT_LAYOUT: DockLayout = { beside: [], stacked: false, sizes: [1], height: 300 };

interface KeyValue { getItem(key: string): string | null; setItem(key: string, value: string): void; removeItem(key: string): void }

const key = (user: string, role: string) => `modd.dock.${user}.${role}`;
const clamp = (x: number, lo: number, hi: number) => Math.min(hi, Math.max(lo, x));
const equal = (n: number) => Array.from({ length: n }, () => 1 / n);

/** n shares, each about MIN_SHARE at least, summing to 1 (equal ones when `v` is not n positive numbers). */
function shares(v: unknown, n: number): number[] {
  if (!Array.isArray(v) || v.length !== n || !v.every((x) => typeof x === "number" && Number.isFinite(x) && x > 0)) return equal(n);
  const total = (v as number[]).reduce((a, b) => a + b, 0);
  const floored = (v as number[]).map((x) => Math.max(MIN_SHARE, x / total));
  const sum = floored.reduce((a, b) => a + b, 0);
  return floored.map((x) => x / sum);
}

/**
 * A layout with every field in range (anything unreadable is the default's).
 * Reads the earlier form too: `beside` one panel id and `split` the tab panel's share.
 */
export function sanitize(v: unknown, panels: readonly string[]): DockLayout {
  const o = (v && typeof v === "object" ? v : {}) as Record<string, unknown>;
  const listed: unknown[] = typeof o.beside === "string" ? [o.beside] : Array.isArray(o.beside) ? o.beside : [];
  const beside = [...new Set(listed.filter((p): p is PanelId => typeof p === "string" && panels.includes(p)))].slice(0, MAX_BESIDE);
  const split = typeof o.split === "number" && Number.isFinite(o.split) ? clamp(o.split, 0.2, 0.8) : null;
  const sizes = Array.isArray(o.sizes) ? shares(o.sizes, beside.length + 1)
    : split !== null && beside.length === 1 ? [split, 1 - split] : equal(beside.length + 1);
  const height = typeof o.height === "number" && Number.isFinite(o.height) ? clamp(Math.round(o.height), 160, 900) : DEFAULT_LAYOUT.height;
  return { beside, stacked: o.stacked === true, sizes, height };
}

/** The layout with panel `id` (or none: null) in place `index` of the panels beside; the panes share the room equally again. */
export function setBeside(layout: DockLayout, index: number, id: PanelId | null): DockLayout {
  const beside = layout.beside.slice(0, index).concat(id ? [id] : [], layout.beside.slice(index + 1));
  const unique = [...new Set(beside)].slice(0, MAX_BESIDE);
  return { ...layout, beside: unique, sizes: equal(unique.length + 1) };
}

/** The shares after divider `i` (between pane i and i+1) moved by `delta` of the room; each pane keeps MIN_SHARE. */
export function moveDivider(sizes: readonly number[], i: number, delta: number): number[] {
  if (i < 0 || i + 1 >= sizes.length) return [...sizes];
  const pair = sizes[i] + sizes[i + 1];
  const first = clamp(sizes[i] + delta, MIN_SHARE, pair - MIN_SHARE);
  const next = [...sizes];
  next[i] = first;
  next[i + 1] = pair - first;
  return next;
}

export function isDefault(layout: DockLayout): boolean {
  return layout.beside.length === 0 && !layout.stacked && layout.height === DEFAULT_LAYOUT.height;
}

export function loadLayout(store: KeyValue, user: string, role: string, panels: readonly string[]): DockLayout {
  try {
    const raw = store.getItem(key(user, role));
    return raw ? sanitize(JSON.parse(raw), panels) : DEFAULT_LAYOUT;
  } catch {
    return DEFAULT_LAYOUT; // storage off or a value not JSON
  }
}

export function saveLayout(store: KeyValue, user: string, role: string, layout: DockLayout): void {
  try { store.setItem(key(user, role), JSON.stringify(layout)); } catch { /* storage off: not remembered */ }
}

export function resetLayout(store: KeyValue, user: string, role: string): DockLayout {
  try { store.removeItem(key(user, role)); } catch { /* */ }
  return DEFAULT_LAYOUT;
}
