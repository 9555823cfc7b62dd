import { describe, expect, it } from "vitest";
import { DEFAULT_LAYOUT, MIN_SHARE, isDefault, loadLayout, moveDivider, resetLayout, sanitize, saveLayout, setBeside } from "./dockLayout";

function memory() {
  const m = new Map<string, string>();
  return { getItem: (k: string) => m.get(k) ?? null, setItem: (k: string, v: string) => void m.set(k, v), removeItem: (k: string) => void m.delete(k) };
}
const PANELS = ["plan", "monitor", "map"];
const sum = (xs: number[]) => xs.reduce((a, b) => a + b, 0);

describe("dock layout", () => {
  it("is remembered per user and role, and reset in one call", () => {
    const s = memory();
    const three = { beside: ["map" as const, "plan" as const], stacked: true, sizes: [0.5, 0.3, 0.2], height: 420 };
    saveLayout(s, "ana", "scientist", three);
    expect(loadLayout(s, "ana", "scientist", PANELS)).toEqual(three);
    expect(loadLayout(s, "ana", "operator", PANELS)).toEqual(DEFAULT_LAYOUT);
    expect(loadLayout(s, "bob", "scientist", PANELS)).toEqual(DEFAULT_LAYOUT);
    expect(resetLayout(s, "ana", "scientist")).toEqual(DEFAULT_LAYOUT);
    expect(loadLayout(s, "ana", "scientist", PANELS)).toEqual(DEFAULT_LAYOUT);
  });

  it("keeps what it reads in range", () => {
    expect(sanitize({ beside: ["nope"], sizes: [5], height: 10 }, PANELS)).toEqual({ beside: [], stacked: false, sizes: [1], height: 160 });
    expect(sanitize("junk", PANELS)).toEqual(DEFAULT_LAYOUT);
    // at most two beside, each once; shares that do not match the panes are made equal
    const l = sanitize({ beside: ["map", "map", "plan", "monitor"], sizes: [0.9, 0.1] }, PANELS);
    expect(l.beside).toEqual(["map", "plan"]);
    expect(l.sizes.map((x) => x.toFixed(3))).toEqual(["0.333", "0.333", "0.333"]);
    // shares below the least are raised, and they still sum to 1
    const tiny = sanitize({ beside: ["map"], sizes: [0.99, 0.01] }, PANELS).sizes;
    expect(sum(tiny)).toBeCloseTo(1);
    expect(Math.min(...tiny)).toBeGreaterThanOrEqual(MIN_SHARE - 0.02);
    const s = memory();
    s.setItem("modd.dock.ana.scientist", "{not json");
    expect(loadLayout(s, "ana", "scientist", PANELS)).toEqual(DEFAULT_LAYOUT);
  });

  it("reads the layout an earlier version remembered (one panel beside, the tab's share)", () => {
    expect(sanitize({ beside: "map", split: 0.4, height: 420 }, PANELS)).toEqual({ beside: ["map"], stacked: false, sizes: [0.4, 0.6], height: 420 });
    expect(sanitize({ beside: null, split: 0.4, height: 300 }, PANELS)).toEqual(DEFAULT_LAYOUT);
  });

  it("adds, changes and removes the panels beside; the panes share the room again", () => {
    const two = setBeside(DEFAULT_LAYOUT, 0, "map");
    expect(two).toMatchObject({ beside: ["map"], sizes: [0.5, 0.5] });
    const three = setBeside(two, 1, "plan");
    expect(three.beside).toEqual(["map", "plan"]);
    expect(three.sizes).toHaveLength(3);
    expect(setBeside(three, 0, null).beside).toEqual(["plan"]);
    expect(setBeside(three, 1, "map").beside).toEqual(["map"]); // never twice
    expect(isDefault(DEFAULT_LAYOUT)).toBe(true);
    expect(isDefault(three)).toBe(false);
    expect(isDefault({ ...DEFAULT_LAYOUT, stacked: true })).toBe(false);
  });

  it("moves one divider: its two panes trade room, the others keep theirs, none below the least", () => {
    const moved = moveDivider([0.4, 0.3, 0.3], 1, 0.1);
    expect(moved[0]).toBe(0.4);
    expect(moved[1]).toBeCloseTo(0.4);
    expect(moved[2]).toBeCloseTo(0.2);
    expect(moveDivider([0.5, 0.5], 0, -1)).toEqual([MIN_SHARE, 1 - MIN_SHARE]);
    expect(moveDivider([0.5, 0.5], 1, 0.1)).toEqual([0.5, 0.5]); // no such divider
  });
});
