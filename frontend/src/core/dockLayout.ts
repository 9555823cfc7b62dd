/**
 * The dock's arrangement: the tab panel alone, or a second panel beside it
 * (map beside the Monitor, say), their share of the width, and the dock's
 * height; remembered per user and role (in this browser) and reset in one
 * click. Pure: reading and writing go through a Storage-like object.
 *
 * @example
 *   saveLayout(localStorage, "ana", "scientist", { beside: "map", split: 0.5, height: 360 })
 *   loadLayout(localStorage, "ana", "scientist").beside // "map"
 */
import type { PanelId } from "../editor/store";

export interface DockLayout {
  /** The panel shown beside the tab panel, or null: one panel. */
  beside: PanelId | null;
  /** The tab panel's share of the width, 0.2–0.8. */
  split: number;
  /** The dock's height in CSS pixels, 160–900. */
  height: number;
}

export const DEFAULT_LAYOUT: DockLayout = { beside: null, split: 0.5, height: 300 };

interface KeyValue { getItem(key: string): string | null; setItem(key: string, value: string): void; removeItem(key: string): void }

const key = (user: string, role: string) => `modd.dock.${user}.${role}`;
const clamp = (x: number, lo: number, hi: number) => Math.min(hi, Math.max(lo, x));

/** A layout with every field in range (anything unreadable is the default's). */
export function sanitize(v: unknown, panels: readonly string[]): DockLayout {
  const o = (v && typeof v === "object" ? v : {}) as Record<string, unknown>;
  const beside = typeof o.beside === "string" && panels.includes(o.beside) ? (o.beside as PanelId) : null;
  const split = typeof o.split === "number" && Number.isFinite(o.split) ? clamp(o.split, 0.2, 0.8) : DEFAULT_LAYOUT.split;
  const height = typeof o.height === "number" && Number.isFinite(o.height) ? clamp(Math.round(o.height), 160, 900) : DEFAULT_LAYOUT.height;
  return { beside, split, height };
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
