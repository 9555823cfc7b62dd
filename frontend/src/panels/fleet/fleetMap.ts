/**
 * Every drone of a campaign on one map: their last fixes placed on a canvas,
 * north up, equal scale on both axes (local metres around the fixes' middle,
 * equirectangular: a lake or a bay, not a continent), each dot labelled with
 * its drone and coloured by its link state.
 *
 * @example
 *   fleetLayout([{ name: "a", lat: 45, lon: 6 }, { name: "b", lat: 45.001, lon: 6 }], 200, 100, 10)
 *   // [{ name: "a", x: 100, y: 90 }, { name: "b", x: 100, y: 10 }]   (b is 111 m north)
 */
import { EARTH_RADIUS_M } from "../../core/track";

export interface Fix { name: string; lat: number; lon: number }
export interface Placed { name: string; x: number; y: number }

/** Where each fix goes on a width × height canvas with a margin (CSS pixels). */
export function fleetLayout(fixes: readonly Fix[], width: number, height: number, margin: number): Placed[] {
  if (!fixes.length) return [];
  const lat0 = (Math.min(...fixes.map((f) => f.lat)) + Math.max(...fixes.map((f) => f.lat))) / 2;
  const lon0 = (Math.min(...fixes.map((f) => f.lon)) + Math.max(...fixes.map((f) => f.lon))) / 2;
  const rad = Math.PI / 180;
  const metres = fixes.map((f) => ({
    name: f.name,
    east: (f.lon - lon0) * rad * EARTH_RADIUS_M * Math.cos(lat0 * rad),
    north: (f.lat - lat0) * rad * EARTH_RADIUS_M,
  }));
  const spanE = Math.max(...metres.map((m) => Math.abs(m.east))) * 2;
  const spanN = Math.max(...metres.map((m) => Math.abs(m.north))) * 2;
  const w = Math.max(1, width - 2 * margin), h = Math.max(1, height - 2 * margin);
  const scale = Math.min(spanE > 0 ? w / spanE : Infinity, spanN > 0 ? h / spanN : Infinity);
  const s = Number.isFinite(scale) ? scale : 0; // one fix, or all at one place: the middle
  return metres.map((m) => ({ name: m.name, x: width / 2 + m.east * s, y: height / 2 - m.north * s }));
}

const LINK_COLOURS: Record<string, string> = { up: "#2e7d32", connecting: "#f9a825", down: "#c62828" };

/** The colour of a link state (grey: not reporting). */
export function linkColour(state: string | null): string {
  return state ? LINK_COLOURS[state] ?? "#757575" : "#9e9e9e";
}

/** Draws the placed drones; returns where each was drawn. */
export function drawFleet(canvas: HTMLCanvasElement, fixes: readonly Fix[], links: Record<string, string | null>): Placed[] {
  const width = canvas.clientWidth || 400, height = canvas.clientHeight || 240;
  const ratio = window.devicePixelRatio || 1;
  canvas.width = width * ratio;
  canvas.height = height * ratio;
  const placed = fleetLayout(fixes, width, height, 30);
  const ctx = canvas.getContext("2d");
  if (!ctx) return placed;
  ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
  ctx.clearRect(0, 0, width, height);
  ctx.font = "12px sans-serif";
  const labels = new Map<string, number>(); // drones within a few pixels: their labels stacked
  for (const p of placed) {
    const spot = `${Math.round(p.x / 8)},${Math.round(p.y / 8)}`;
    const below = labels.get(spot) ?? 0;
    labels.set(spot, below + 1);
    ctx.fillStyle = linkColour(links[p.name] ?? null);
    ctx.beginPath();
    ctx.arc(p.x, p.y, 6, 0, 2 * Math.PI);
    ctx.fill();
    ctx.fillStyle = "#222";
    ctx.fillText(p.name, p.x + 9, p.y + 4 + 14 * below);
  }
  return placed;
}
