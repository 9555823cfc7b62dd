// @vitest-environment jsdom
import { describe, expect, it } from "vitest";
import { drawMap, fitScale, isLocalTiles, tileOrigin, tileUrlProblem } from "./drawMap";
import type { TrackPoint } from "../../core/track";

describe("tile URL", () => {
  it("takes an http(s) template with {z}, {x} and {y}, and says what is wrong otherwise", () => {
    expect(tileUrlProblem("")).toBeNull();
    expect(tileUrlProblem("https://tile.openstreetmap.org/{z}/{x}/{y}.png")).toBeNull();
    expect(tileUrlProblem("https://tile.openstreetmap.org/{z}/{x}.png")).toBe("a tile URL needs {y}");
    expect(tileUrlProblem("ftp://tiles/{z}/{x}/{y}")).toMatch(/http/);
    expect(tileUrlProblem("javascript:alert(1)//{z}{x}{y}")).toMatch(/http/);
    expect(tileUrlProblem("http://a b/{z}/{x}/{y}")).toBe("not a URL");
    expect(tileOrigin("http://127.0.0.1:8123/{z}/{x}/{y}.png")).toBe("http://127.0.0.1:8123");
  });
});

/** A canvas of the given CSS size whose 2D context draws nothing and gives up after `limit` calls (a drawing that never ends). */
function canvasOf(width: number, height: number, limit = 100_000) {
  let calls = 0;
  const ctx = new Proxy({}, {
    get: (_t, name) => (name === "measureText" ? () => ({ width: 10 }) : () => {
      calls += 1;
      if (calls > limit) throw new Error(`the drawing did not end (${String(name)} called ${limit} times)`);
    }),
    set: () => true,
  });
  return { clientWidth: width, clientHeight: height, width: 0, height: 0, dataset: {}, getContext: () => ctx } as unknown as HTMLCanvasElement;
}

describe("map in a narrow panel", () => {
  const track: TrackPoint[] = [0, 1, 2].map((i) => ({ t: i, east: 0, north: 4 * i, lat: 0, lon: 0, value: null }));

  it("has no scale when the canvas cannot hold the margins", () => {
    expect(fitScale(400, 300, 20, 20)).toBeCloseTo(12.2);
    expect(fitScale(40, 300, 20, 20)).toBeNull(); // 40 px wide: the margins alone take 56
    expect(fitScale(400, 56, 20, 20)).toBeNull();
  });

  it("ends its drawing however narrow the canvas (three panels side by side left the map ~20 px: the grid's loop never ended)", () => {
    for (const [w, h] of [[20, 300], [56, 300], [400, 30], [1, 1], [400, 300]]) {
      expect(() => drawMap(canvasOf(w, h), track, null, { tileUrl: "", onTile: () => undefined })).not.toThrow();
    }
  });
});

describe("the vehicle's heading", () => {
  const east: TrackPoint[] = [0, 1, 2].map((i) => ({ t: i, east: 10 * i, north: 0, lat: 0, lon: 0, value: null }));
  it("is the heading topic's value when there is one, else the course over the last fixes", () => {
    expect(drawMap(canvasOf(400, 300), east, null, { tileUrl: "", onTile: () => undefined }).heading).toBeCloseTo(90);
    expect(drawMap(canvasOf(400, 300), east, null, { tileUrl: "", onTile: () => undefined, heading: 370 }).heading).toBeCloseTo(10);
    expect(drawMap(canvasOf(400, 300), east, null, { tileUrl: "", onTile: () => undefined, heading: null }).heading).toBeCloseTo(90);
    expect(drawMap(canvasOf(400, 300), east, null, { tileUrl: "", onTile: () => undefined, heading: Number.NaN }).heading).toBeCloseTo(90);
  });
});

describe("the workbench's tile folder", () => {
  it("is a tile URL of the page's own origin", () => {
    expect(isLocalTiles("/api/tiles/{z}/{x}/{y}.png")).toBe(true);
    expect(tileUrlProblem("/api/tiles/{z}/{x}/{y}.png")).toBeNull();
    expect(tileUrlProblem("/elsewhere/{z}/{x}/{y}.png")).toMatch(/api\/tiles/);
    expect(tileOrigin("/api/tiles/{z}/{x}/{y}.png")).toBe(window.location.origin);
  });
});
