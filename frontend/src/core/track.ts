/**
 * The drone's track for the 2D map, from delivered values: which
 * subscriptions carry its position (by variable name, as the backend's 3D
 * scene reads them: backend/src/modd_backend/scene.py), the fixes in local
 * metres east/north of the first one, each coloured by the chosen
 * subscription's value at that time, a colour scale with its legend, and a
 * round grid step.
 *
 * @example
 *   positionSubscribers(model)          // { lat: "sub_lat", lon: "sub_lon" }
 *   trackPoints(lat, lon, temperature)  // [{ t, east: 0, north: 0, value: 12.1 }, ...]
 */
import { AGGREGATION } from "./contracts.gen";
import type { ModdModel } from "./model.gen";
import type { Sample } from "../dataSources/types";

const ROLE_NAMES = { lat: ["latitude", "lat"], lon: ["longitude", "lon", "lng"] } as const;
export const EARTH_RADIUS_M = 6_371_000;

/** The first subscriptions whose topics are a latitude and a longitude. */
export function positionSubscribers(model: ModdModel): { lat: string | null; lon: string | null } {
  const find = (names: readonly string[]) =>
    model.subscribers.find((s) => names.includes((s.topic.split(".").pop() ?? "").toLowerCase()))?.name ?? null;
  return { lat: find(ROLE_NAMES.lat), lon: find(ROLE_NAMES.lon) };
}

/** Topic names (their last part) that are the vehicle's heading or course over ground, in degrees from north. */
const HEADING_NAMES = ["heading", "true_heading", "hdg", "course", "course_true", "cog"];

/** The first subscription (not a COUNT) whose topic is a heading or course: the map's vehicle points along it. */
export function headingSubscriber(model: ModdModel): string | null {
  return model.subscribers.find((s) => s.aggregation !== AGGREGATION.COUNT && HEADING_NAMES.includes((s.topic.split(".").pop() ?? "").toLowerCase()))?.name ?? null;
}

/** The first topics (full names, e.g. of an archive file) that are a latitude and a longitude. */
export function positionTopics(topics: readonly string[]): { lat: string | null; lon: string | null } {
  const find = (names: readonly string[]) => topics.find((t) => names.includes((t.split(".").pop() ?? "").toLowerCase())) ?? null;
  return { lat: find(ROLE_NAMES.lat), lon: find(ROLE_NAMES.lon) };
}

/** A latitude and a longitude topic that make a track, and how many fixes it has (the fewer of their message counts). */
export interface PositionPair { lat: string; lon: string; fixes: number }

/**
 * Every latitude/longitude pair of an archive file's topics (each latitude with the
 * longitude of the same sensor, else with every longitude when no sensor has both),
 * the pair with the most fixes first: the track a map draws unless the user picks another.
 *
 * @example
 *   positionPairs([{ topic: "usv.gps.latitude", messages: 9 }, { topic: "usv.gps.longitude", messages: 9 },
 *     { topic: "usv.gnss.lat", messages: 40 }, { topic: "usv.gnss.lon", messages: 41 }])
 *   // [{ lat: "usv.gnss.lat", lon: "usv.gnss.lon", fixes: 40 }, { lat: "usv.gps.latitude", lon: "usv.gps.longitude", fixes: 9 }]
 */
export function positionPairs(topics: ReadonlyArray<{ topic: string; messages: number }>): PositionPair[] {
  const role = (names: readonly string[]) => topics.filter((t) => names.includes((t.topic.split(".").pop() ?? "").toLowerCase()));
  const lats = role(ROLE_NAMES.lat), lons = role(ROLE_NAMES.lon);
  const sensor = (t: string) => t.slice(0, t.lastIndexOf("."));
  const pair = (a: { topic: string; messages: number }, b: { topic: string; messages: number }) =>
    ({ lat: a.topic, lon: b.topic, fixes: Math.min(a.messages, b.messages) });
  const same = lats.flatMap((a) => lons.filter((b) => sensor(b.topic) === sensor(a.topic)).map((b) => pair(a, b)));
  const pairs = same.length ? same : lats.flatMap((a) => lons.map((b) => pair(a, b)));
  return pairs.sort((x, y) => y.fixes - x.fixes);
}

export interface TrackPoint { t: number; east: number; north: number; lat: number; lon: number; value: number | null }

/** The sample of a sorted series at or before `t` (binary search), or null. */
export function valueAt(series: readonly Sample[], t: number): number | null {
  let lo = 0, hi = series.length - 1, found = -1;
  while (lo <= hi) {
    const mid = (lo + hi) >> 1;
    if (series[mid].t <= t + 1e-6) { found = mid; lo = mid + 1; } else hi = mid - 1;
  }
  return found < 0 ? null : series[found].value;
}

/**
 * Fixes where a latitude and a longitude arrived together (within `pairS`),
 * in metres from the first fix (equirectangular: fine over a survey area).
 */
export function trackPoints(lat: readonly Sample[], lon: readonly Sample[], colour: readonly Sample[] = [], pairS = 0.5): TrackPoint[] {
  const out: TrackPoint[] = [];
  let j = 0;
  for (const a of lat) {
    while (j < lon.length - 1 && lon[j + 1].t <= a.t + 1e-6) j += 1;
    const candidates = [lon[j], lon[j + 1]].filter((b): b is Sample => b !== undefined);
    const b = candidates.sort((x, y) => Math.abs(x.t - a.t) - Math.abs(y.t - a.t))[0];
    if (!b || Math.abs(b.t - a.t) > pairS) continue;
    out.push({ t: a.t, lat: a.value, lon: b.value, east: 0, north: 0, value: colour.length ? valueAt(colour, a.t) : null });
  }
  if (out.length === 0) return out;
  const lat0 = out[0].lat, lon0 = out[0].lon;
  const k = (Math.PI / 180) * EARTH_RADIUS_M;
  for (const p of out) {
    p.east = (p.lon - lon0) * k * Math.cos((lat0 * Math.PI) / 180);
    p.north = (p.lat - lat0) * k;
  }
  return out;
}

/** Blue (low) through green to red (high), as the 3D scene colours its track. */
export function colourOf(x: number): [number, number, number] {
  const t = Math.min(1, Math.max(0, Number.isFinite(x) ? x : 0));
  return t < 0.5 ? [0, Math.round(510 * t), Math.round(255 * (1 - 2 * t))] : [Math.round(510 * (t - 0.5)), Math.round(255 * (2 - 2 * t)), 0];
}

/** The values' range for the legend (null without values). */
export function valueRange(points: readonly TrackPoint[]): [number, number] | null {
  const v = points.map((p) => p.value).filter((x): x is number => x !== null);
  if (!v.length) return null;
  return [Math.min(...v), Math.max(...v)];
}

/** A round grid step in metres (1, 2 or 5 × 10^n) giving about `lines` lines over `span` metres. */
export function gridStep(span: number, lines = 6): number {
  const raw = Math.max(span, 1) / lines;
  const p = 10 ** Math.floor(Math.log10(raw));
  return [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw) ?? 10 * p;
}

/** "40 m", "1.2 km". */
export function formatDistance(m: number): string {
  return m >= 1000 ? `${Number((m / 1000).toFixed(2))} km` : `${Number(m.toFixed(1))} m`;
}

/**
 * The recorded fixes (the base station's record since the mission began: [t, lat, lon])
 * before a live series: the record's samples older than the live series' first, then the
 * live ones. `column` 1 takes the latitudes, 2 the longitudes, 3 the colour values (those the record has).
 */
export function withRecord(record: ReadonlyArray<readonly [number, number, number, (number | null)?]>, column: 1 | 2 | 3, live: readonly Sample[]): Sample[] {
  const first = live.length ? live[0].t : Infinity;
  const before: Sample[] = [];
  for (const r of record) {
    const v = r[column];
    if (r[0] < first - 1e-6 && typeof v === "number") before.push({ t: r[0], value: v });
  }
  return before.length ? before.concat(live) : [...live];
}
