import { describe, expect, it } from "vitest";
import { fleetLayout, linkColour } from "./fleetMap";

/** Great-circle distance (haversine), the oracle the layout's flat metres must agree with over a lake. */
function haversine(a: { lat: number; lon: number }, b: { lat: number; lon: number }): number {
  const r = Math.PI / 180, R = 6_371_000;
  const dLat = (b.lat - a.lat) * r, dLon = (b.lon - a.lon) * r;
  const h = Math.sin(dLat / 2) ** 2 + Math.cos(a.lat * r) * Math.cos(b.lat * r) * Math.sin(dLon / 2) ** 2;
  return 2 * R * Math.asin(Math.sqrt(h));
}

describe("fleetLayout", () => {
  const fixes = [
    { name: "a", lat: 45.0, lon: 6.0 },
    { name: "b", lat: 45.002, lon: 6.0 },
    { name: "c", lat: 45.001, lon: 6.003 },
  ];

  it("puts north up, east right, one scale on both axes (distances as the haversine says)", () => {
    const placed = fleetLayout(fixes, 400, 300, 20);
    const at = Object.fromEntries(placed.map((p) => [p.name, p]));
    expect(at.b.y).toBeLessThan(at.a.y);           // b is north of a
    expect(at.a.x).toBeCloseTo(at.b.x, 6);         // same longitude, same column
    expect(at.c.x).toBeGreaterThan(at.a.x);        // c is east
    const px = (p: string, q: string) => Math.hypot(at[p].x - at[q].x, at[p].y - at[q].y);
    const ratio = px("a", "b") / haversine(fixes[0], fixes[1]);
    expect(px("a", "c") / haversine(fixes[0], fixes[2])).toBeCloseTo(ratio, 3);
    expect(px("b", "c") / haversine(fixes[1], fixes[2])).toBeCloseTo(ratio, 3);
  });

  it("stays inside the canvas and its margin", () => {
    for (const p of fleetLayout(fixes, 400, 300, 20)) {
      expect(p.x).toBeGreaterThanOrEqual(20 - 1e-9);
      expect(p.x).toBeLessThanOrEqual(380 + 1e-9);
      expect(p.y).toBeGreaterThanOrEqual(20 - 1e-9);
      expect(p.y).toBeLessThanOrEqual(280 + 1e-9);
    }
  });

  it("puts a lone drone, or drones at one place, in the middle", () => {
    expect(fleetLayout([fixes[0]], 200, 100, 10)).toEqual([{ name: "a", x: 100, y: 50 }]);
    expect(fleetLayout([fixes[0], { ...fixes[0], name: "z" }], 200, 100, 10).map((p) => [p.x, p.y])).toEqual([[100, 50], [100, 50]]);
    expect(fleetLayout([], 200, 100, 10)).toEqual([]);
  });

  it("colours a link by its state, grey when not reporting", () => {
    expect(linkColour("up")).not.toBe(linkColour("down"));
    expect(linkColour(null)).toBe("#9e9e9e");
  });
});
