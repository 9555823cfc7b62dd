/**
 * Draws the track on a 2D canvas: fit to the canvas with a margin, north up,
 * equal scale on both axes; a metre grid at a round step, a scale bar,
 * optional web-mercator tiles under it, then the fixes coloured by value
 * (grey when the colour subscription had no value yet) joined by a thin line.
 */
import { colourOf, EARTH_RADIUS_M, formatDistance, gridStep, type TrackPoint } from "../../core/track";
import { courseDeg } from "./marker";

interface Options {
  tileUrl: string;
  onTile: () => void;
  /** The vehicle's heading from a heading/course topic, degrees from north; without it, its course over the last fixes. */
  heading?: number | null;
}

/** The tiles a drawing asked for: drawn, failed (unreachable, refused by the page's policy, not an image), waiting. */
export interface TileCount { asked: number; drawn: number; failed: number }

/** What a drawing did: where (CSS pixels in the canvas) up to 40 of the fixes were drawn, and its tiles. */
export interface Drawn { px: Array<[number, number]>; tiles: TileCount; /** The vehicle's course drawn, degrees from north (null: unknown). */ heading: number | null }

const tiles = new Map<string, HTMLImageElement>();
const failedTiles = new Set<string>();
const MAX_TILES_KEPT = 512;

function tile(url: string, onChange: () => void): HTMLImageElement | "failed" | null {
  if (failedTiles.has(url)) return "failed";
  let img = tiles.get(url);
  if (!img) {
    if (tiles.size >= MAX_TILES_KEPT) tiles.delete(tiles.keys().next().value as string);
    img = new Image();
    img.crossOrigin = "anonymous"; // keeps the canvas readable; tile servers answer CORS (OSM does)
    img.onload = onChange;
    img.onerror = () => { failedTiles.add(url); tiles.delete(url); onChange(); };
    img.src = url;
    tiles.set(url, img);
  }
  return img.complete && img.naturalWidth > 0 ? img : null;
}

/** A tile URL template the map can use: http(s), or a path of the workbench's own (its tile folder, /api/tiles/…), with {z}, {x} and {y}; else why not. */
export function tileUrlProblem(url: string): string | null {
  if (!url) return null;
  if (!/^https?:\/\/[^/]+\//.test(url) && !isLocalTiles(url)) return "a tile URL starts with http:// or https:// and a host, or is the workbench's /api/tiles/…";
  const missing = ["{z}", "{x}", "{y}"].filter((p) => !url.includes(p));
  if (missing.length) return `a tile URL needs ${missing.join(", ")}`;
  try { new URL(tileOrigin(url)); } catch { return "not a URL"; }
  return null;
}

/** A path of the workbench's own tile folder (modd-backend --tiles). */
export function isLocalTiles(url: string): boolean {
  return url.startsWith("/api/tiles/");
}

/** The origin (scheme://host:port) a tile URL template loads from (the page's own for the workbench's tile folder). */
export function tileOrigin(url: string): string {
  return new URL(url.replace(/\{[xyz]\}/g, "0"), window.location.origin).origin;
}

/** The track's margin on every side, in CSS pixels. */
const MARGIN = 28;

/**
 * Pixels per metre that fit a track of extent dx × dy (at least 10 m) in a
 * w × h canvas with MARGIN all round; null when the canvas cannot hold the
 * margins (a map in a narrow panel: a scale of 0 or less would never end the
 * grid's loops).
 */
export function fitScale(w: number, h: number, dx: number, dy: number): number | null {
  const s = Math.min((w - 2 * MARGIN) / Math.max(dx, 10), (h - 2 * MARGIN) / Math.max(dy, 10));
  return s > 0 && Number.isFinite(s) ? s : null;
}

/** Draws the map; see `Drawn`. */
export function drawMap(el: HTMLCanvasElement, points: readonly TrackPoint[], range: [number, number] | null, opts: Options): Drawn {
  const tileCount: TileCount = { asked: 0, drawn: 0, failed: 0 };
  const dpr = window.devicePixelRatio || 1;
  // The drawing is the size the canvas is shown at (CSS pixels), so fix positions match the screen.
  const w = Math.max(el.clientWidth, 1), h = Math.max(el.clientHeight, 1);
  el.width = Math.round(w * dpr);
  el.height = Math.round(h * dpr);
  const ctx = el.getContext("2d");
  if (!ctx) return { px: [], tiles: tileCount, heading: null };
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.fillStyle = "#f8fafc";
  ctx.fillRect(0, 0, w, h);
  ctx.font = "11px system-ui, sans-serif";
  if (points.length === 0) {
    ctx.fillStyle = "#64748b";
    ctx.fillText("waiting for positions…", 12, 20);
    return { px: [], tiles: tileCount, heading: null };
  }
  const xs = points.map((p) => p.east), ys = points.map((p) => p.north);
  const minX = Math.min(...xs), maxX = Math.max(...xs), minY = Math.min(...ys), maxY = Math.max(...ys);
  const span = Math.max(maxX - minX, maxY - minY, 10);
  const s = fitScale(w, h, maxX - minX, maxY - minY);
  if (s === null) {
    ctx.fillStyle = "#64748b";
    ctx.fillText("too small to draw", 2, 12);
    return { px: [], tiles: tileCount, heading: null };
  }
  const cx = (minX + maxX) / 2, cy = (minY + maxY) / 2;
  const X = (e: number) => w / 2 + (e - cx) * s;
  const Y = (n: number) => h / 2 - (n - cy) * s;

  if (opts.tileUrl && !tileUrlProblem(opts.tileUrl)) drawTiles(ctx, points[0], s, X, Y, w, h, opts, tileCount);

  // Grid at a round step, labelled on the left and bottom.
  const step = gridStep(span);
  ctx.strokeStyle = "#e2e8f0";
  ctx.fillStyle = "#94a3b8";
  ctx.lineWidth = 1;
  for (let e = Math.floor((cx - w / 2 / s) / step) * step; X(e) <= w; e += step) {
    ctx.beginPath(); ctx.moveTo(X(e), 0); ctx.lineTo(X(e), h); ctx.stroke();
    ctx.fillText(`${Math.round(e)}`, X(e) + 2, h - 4);
  }
  for (let n = Math.floor((cy - h / 2 / s) / step) * step; Y(n) >= 0; n += step) {
    ctx.beginPath(); ctx.moveTo(0, Y(n)); ctx.lineTo(w, Y(n)); ctx.stroke();
    ctx.fillText(`${Math.round(n)}`, 2, Y(n) - 2);
  }

  // The track: a thin line, then each fix in its colour.
  ctx.strokeStyle = "rgba(71, 85, 105, 0.5)";
  ctx.beginPath();
  points.forEach((p, i) => (i ? ctx.lineTo(X(p.east), Y(p.north)) : ctx.moveTo(X(p.east), Y(p.north))));
  ctx.stroke();
  const [lo, hi] = range ?? [0, 1];
  for (const p of points) {
    const [r, g, b] = p.value === null ? [148, 163, 184] : colourOf((p.value - lo) / (hi - lo || 1));
    ctx.fillStyle = `rgb(${r}, ${g}, ${b})`;
    ctx.beginPath();
    ctx.arc(X(p.east), Y(p.north), 3.5, 0, 2 * Math.PI);
    ctx.fill();
  }
  const last = points[points.length - 1];
  const heading = opts.heading != null && Number.isFinite(opts.heading) ? ((opts.heading % 360) + 360) % 360 : courseDeg(points);
  drawVehicle(ctx, X(last.east), Y(last.north), heading);

  // Scale bar (one grid step) and north arrow.
  ctx.fillStyle = "#0f172a";
  ctx.fillRect(w - 16 - step * s, h - 22, step * s, 3);
  ctx.fillText(formatDistance(step), w - 16 - step * s, h - 26);
  ctx.fillText("N ↑", w - 28, 16);
  const every = Math.max(1, Math.ceil(points.length / 40));
  return { px: points.filter((_, i) => i % every === 0).map((p) => [Math.round(X(p.east)), Math.round(Y(p.north))]), tiles: tileCount, heading };
}

/** The vehicle at its last fix: an arrow along its course (a ring while the course is unknown). */
function drawVehicle(ctx: CanvasRenderingContext2D, x: number, y: number, heading: number | null): void {
  ctx.strokeStyle = "#ffffff";
  ctx.fillStyle = "#0f172a";
  ctx.lineWidth = 2;
  if (heading === null) {
    ctx.beginPath(); ctx.arc(x, y, 6, 0, 2 * Math.PI); ctx.stroke();
    return;
  }
  ctx.save();
  ctx.translate(x, y);
  ctx.rotate((heading * Math.PI) / 180); // canvas y points down: 0° (north) is up
  ctx.beginPath(); ctx.moveTo(0, -11); ctx.lineTo(7, 8); ctx.lineTo(0, 4); ctx.lineTo(-7, 8); ctx.closePath();
  ctx.fill(); ctx.stroke();
  ctx.restore();
}

function drawTiles(ctx: CanvasRenderingContext2D, origin: TrackPoint, s: number, X: (e: number) => number, Y: (n: number) => number,
  w: number, h: number, opts: Options, count: TileCount): void {
  const lat0 = origin.lat, lon0 = origin.lon;
  const cos0 = Math.cos((lat0 * Math.PI) / 180);
  const z = Math.max(0, Math.min(19, Math.round(Math.log2((156543.03 * cos0 * s)))));
  const n = 2 ** z;
  const toTile = (lat: number, lon: number) => {
    const r = (lat * Math.PI) / 180;
    return [((lon + 180) / 360) * n, ((1 - Math.log(Math.tan(r) + 1 / Math.cos(r)) / Math.PI) / 2) * n];
  };
  const fromTile = (tx: number, ty: number) => {
    const lon = (tx / n) * 360 - 180;
    const lat = (Math.atan(Math.sinh(Math.PI * (1 - (2 * ty) / n))) * 180) / Math.PI;
    const k = (Math.PI / 180) * EARTH_RADIUS_M;
    return [X((lon - lon0) * k * cos0), Y((lat - lat0) * k)];
  };
  const k = (Math.PI / 180) * EARTH_RADIUS_M;
  const corner = (px: number, py: number) => toTile(lat0 + (-(py - Y(0)) / s) / k, lon0 + ((px - X(0)) / s) / (k * cos0));
  const [x0, y0] = corner(0, 0), [x1, y1] = corner(w, h);
  for (let tx = Math.floor(x0); tx <= Math.floor(x1) && tx - Math.floor(x0) < 16; tx += 1) {
    for (let ty = Math.floor(y0); ty <= Math.floor(y1) && ty - Math.floor(y0) < 16; ty += 1) {
      const url = opts.tileUrl.replace("{z}", String(z)).replace("{x}", String(tx)).replace("{y}", String(ty));
      const img = tile(url, opts.onTile);
      count.asked += 1;
      if (img === "failed") count.failed += 1;
      if (!img || img === "failed") continue;
      count.drawn += 1;
      const [ax, ay] = fromTile(tx, ty), [bx, by] = fromTile(tx + 1, ty + 1);
      ctx.drawImage(img, ax, ay, bx - ax, by - ay);
    }
  }
}
