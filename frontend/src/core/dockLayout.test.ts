import { describe, expect, it } from "vitest";
import { DEFAULT_LAYOUT, loadLayout, resetLayout, sanitize, saveLayout } from "./dockLayout";

function memory() {
  const m = new Map<string, string>();
  return { getItem: (k: string) => m.get(k) ?? null, setItem: (k: string, v: string) => void m.set(k, v), removeItem: (k: string) => void m.delete(k) };
}
const PANELS = ["plan", "monitor", "map"];

describe("dock layout", () => {
  it("is remembered per user and role, and reset in one call", () => {
    const s = memory();
    saveLayout(s, "ana", "scientist", { beside: "map", split: 0.4, height: 420 });
    expect(loadLayout(s, "ana", "scientist", PANELS)).toEqual({ beside: "map", split: 0.4, height: 420 });
    expect(loadLayout(s, "ana", "operator", PANELS)).toEqual(DEFAULT_LAYOUT);
    expect(loadLayout(s, "bob", "scientist", PANELS)).toEqual(DEFAULT_LAYOUT);
    expect(resetLayout(s, "ana", "scientist")).toEqual(DEFAULT_LAYOUT);
    expect(loadLayout(s, "ana", "scientist", PANELS)).toEqual(DEFAULT_LAYOUT);
  });

  it("keeps what it reads in range", () => {
    expect(sanitize({ beside: "nope", split: 5, height: 10 }, PANELS)).toEqual({ beside: null, split: 0.8, height: 160 });
    expect(sanitize("junk", PANELS)).toEqual(DEFAULT_LAYOUT);
    const s = memory();
    s.setItem("modd.dock.ana.scientist", "{not json");
    expect(loadLayout(s, "ana", "scientist", PANELS)).toEqual(DEFAULT_LAYOUT);
  });
});
