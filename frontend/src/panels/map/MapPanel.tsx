/**
 * Map: the drone's track in 2D, drawn on a canvas (no WebGL), in local
 * metres from its first fix with a grid, a scale bar and north up; each fix
 * coloured by a chosen subscription, with its legend. Tiles are optional (a
 * tile URL such as https://tile.openstreetmap.org/{z}/{x}/{y}.png, kept in
 * this browser; the service must allow its origin, `--tile-origin`):
 * offline, the plain local plot is the map.
 *
 * The positions come from the subscriptions whose topics are a latitude and
 * a longitude (core/track), over the workbench's shared stream, after the
 * fixes the base station recorded since the mission began (its record, via
 * the backend's /track, thinned to 2,000): the whole track after a reload;
 * archive
 * playback hands in its own source and topics (TrackMap), and the map shows
 * the track up to the playback cursor. The colour choice also colours the
 * backend's 3D scene, when it runs one.
 */
import { useDroneName } from "../../app/fleetFocus";
import { subscriptionLabel } from "../../core/topicLabel";
import { useCallback, useEffect, useRef, useState } from "react";
import { headingSubscriber, positionSubscribers, trackPoints, valueRange, withRecord, type TrackPoint } from "../../core/track";
import { unitLabel } from "../../core/chartData";
import { findTopicByName } from "../../core/query";
import { useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { useDroneStream } from "../../app/useDroneStream";
import type { DataSource } from "../../dataSources/types";
import type { RecordTrack } from "../../api/types";
import { drawMap, isLocalTiles, tileOrigin, tileUrlProblem, type TileCount } from "./drawMap";
import { defaultColour } from "./marker";

const TILE_KEY = "modd.map.tileUrl";
/** Fixes of the record asked for at most (the backend thins the mission's evenly). */
const RECORD_POINTS = 2000;

type RecordFixes = RecordTrack["points"];

/** A channel of the source the track can be coloured by. */
export interface ColourChoice { channel: string; label: string; detail: string; unit: string }

function useTrack(source: DataSource, lat: string | null, lon: string | null, colour: string, record: RecordFixes): TrackPoint[] {
  const [points, setPoints] = useState<TrackPoint[]>([]);
  useEffect(() => {
    if (!lat || !lon) { setPoints([]); return; }
    let frame = 0;
    const build = () => setPoints(trackPoints(withRecord(record, 1, source.history(lat)), withRecord(record, 2, source.history(lon)),
      colour ? withRecord(record, 3, source.history(colour)) : []));
    const later = () => { if (!frame) frame = requestAnimationFrame(() => { frame = 0; build(); }); };
    build();
    const offs = [lat, lon, colour].filter(Boolean).map((c) => source.subscribe(c, later));
    return () => { offs.forEach((o) => o()); cancelAnimationFrame(frame); };
  }, [source, lat, lon, colour, record]);
  return points;
}

/** The workbench's own tile URL when it serves a tile folder (modd-backend --tiles), else null. */
function useLocalTiles(): string | null {
  const { api } = useServices();
  const [url, setUrl] = useState<string | null>(null);
  useEffect(() => {
    let live = true;
    api.tilesInfo().then((r) => { if (live) setUrl(r.available ? r.url : null); }, () => undefined);
    return () => { live = false; };
  }, [api]);
  return url;
}

/** The latest value of a channel (null: none yet, or no channel). */
function useLatest(source: DataSource, channel: string | null): number | null {
  const [v, setV] = useState<number | null>(null);
  useEffect(() => {
    if (!channel) { setV(null); return; }
    const read = () => { const h = source.history(channel); setV(h.length ? h[h.length - 1].value : null); };
    read();
    return source.subscribe(channel, read);
  }, [source, channel]);
  return v;
}

interface RecordTrackOf { fixes: RecordFixes; total: number }
/** Asks the backend for the record's fixes, each with the colour channel's value then. */
type RecordSource = (colour: string) => Promise<RecordTrack>;

/** The fixes the base station recorded since the mission began (none until they come, or when it cannot say). */
function useRecordTrack(recordOf: RecordSource | undefined, colour: string): RecordTrackOf {
  const [got, setGot] = useState<RecordTrackOf>(NO_RECORD);
  useEffect(() => {
    if (!recordOf) return;
    let live = true;
    recordOf(colour).then((r) => { if (live) setGot({ fixes: r.points, total: r.total }); }, () => undefined);
    return () => { live = false; };
  }, [recordOf, colour]);
  return got;
}

const NO_RECORD: RecordTrackOf = { fixes: [], total: 0 };

function TileStatus({ url, count }: { url: string; count: TileCount }) {
  const problem = tileUrlProblem(url);
  if (!url) return null;
  if (problem) return <p className="error" role="alert" data-testid="tile-status">Tiles off: {problem}.</p>;
  if (isLocalTiles(url)) {
    return (
      <p className="muted" data-testid="tile-status">
        Tiles: {count.drawn} of {count.asked} drawn from the workbench&apos;s tile folder
        {count.failed > 0 && <>; {count.failed} not in it (modd-backend --tiles DIR holds &lt;z&gt;/&lt;x&gt;/&lt;y&gt;.png)</>}
      </p>
    );
  }
  const origin = tileOrigin(url);
  return (
    <p className={count.failed ? "error" : "muted"} data-testid="tile-status">
      Tiles: {count.drawn} of {count.asked} drawn from {origin}
      {count.failed > 0 && <>; {count.failed} did not load: is {origin} reachable, and allowed by the workbench (modd-backend --tile-origin {origin})?</>}
    </p>
  );
}

interface TrackMapProps {
  source: DataSource;
  lat: string | null;
  lon: string | null;
  choices: readonly ColourChoice[];
  /** Called when the user picks a colour channel ("" for plain). */
  onColour?: (channel: string) => void;
  /** Prefix of the test ids (map, playback-map). */
  id?: string;
  missing: string;
  /** The fixes recorded since the mission began (drawn before the source's first: the whole track after a reload). */
  recordOf?: RecordSource;
  /** A subscription of the vehicle's heading or course (degrees from north): the vehicle points along it. */
  headingChannel?: string | null;
}

export function TrackMap({ source, lat, lon, choices, onColour, id = "map", missing, recordOf, headingChannel = null }: TrackMapProps) {
  const drone = useDroneName();
  const [colour, setColour] = useState(() => defaultColour(choices));
  const [tileUrl, setTileUrl] = useState(() => window.localStorage.getItem(TILE_KEY) ?? "");
  const [tiles, setTiles] = useState<TileCount>({ asked: 0, drawn: 0, failed: 0 });
  const record = useRecordTrack(recordOf, colour);
  const points = useTrack(source, lat, lon, colour, record.fixes);
  const canvas = useRef<HTMLCanvasElement>(null);
  const range = valueRange(points);
  const chosen = choices.find((c) => c.channel === colour);
  const [redraw, setRedraw] = useState(0);
  const [heading, setHeading] = useState<number | null>(null);
  const headingValue = useLatest(source, headingChannel);
  const localTiles = useLocalTiles();

  useEffect(() => {
    const el = canvas.current;
    if (!el) return;
    const ro = new ResizeObserver(() => setRedraw((n) => n + 1));
    ro.observe(el);
    return () => ro.disconnect();
  }, []);
  useEffect(() => {
    const el = canvas.current;
    if (!el) return;
    const drawn = drawMap(el, points, range, { tileUrl, onTile: () => setRedraw((n) => n + 1), heading: headingValue });
    el.dataset.trackPx = JSON.stringify(drawn.px);
    el.dataset.origin = points.length ? `${points[0].lat},${points[0].lon}` : "";
    el.dataset.heading = drawn.heading === null ? "" : drawn.heading.toFixed(0);
    el.dataset.firstT = points.length ? String(points[0].t) : "";
    el.dataset.headingFrom = drawn.heading === null ? "" : headingChannel && headingValue !== null ? "topic" : "track";
    setHeading(drawn.heading === null ? null : Math.round(drawn.heading));
    setTiles((t) => (t.asked === drawn.tiles.asked && t.drawn === drawn.tiles.drawn && t.failed === drawn.tiles.failed ? t : drawn.tiles));
  }, [points, range?.[0], range?.[1], tileUrl, redraw, headingValue]); // eslint-disable-line react-hooks/exhaustive-deps

  const unitSuffix = chosen?.unit ? ` ${chosen.unit}` : "";
  const choose = (channel: string) => { setColour(channel); onColour?.(channel); };

  return (
    <div className="map-panel">
      <canvas ref={canvas} className="map-canvas" role="img" data-testid={`${id}-canvas`} data-points={points.length}
        aria-label={`Track of ${drone}: ${points.length} fixes${chosen ? `, coloured by ${chosen.label}` : ""}`} />
      <aside className="map-legend" aria-label="Map legend">
        <label>Colour by{" "}
          <select aria-label="Colour by" value={colour} onChange={(e) => choose(e.target.value)}>
            <option value="">(plain)</option>
            {choices.map((c) => <option key={c.channel} value={c.channel}>{c.label}: {c.detail}</option>)}
          </select>
        </label>
        {!lat || !lon ? <p className="muted" role="status">{missing}</p>
          : <p className="muted" role="status" data-testid={`${id}-fixes`}>{points.length} fixes from {lat} and {lon}
            {record.total > 0 && <>, the mission&apos;s from its start in the base station&apos;s record ({record.total} recorded{record.total > record.fixes.length ? `, ${record.fixes.length} drawn` : ""})</>}.
            {heading !== null && <> The vehicle heads {heading.toFixed(0)}°{headingChannel && headingValue !== null ? <> (from {headingChannel}, a heading topic)</>
              : <> (its course over the last fixes{headingChannel ? <>: no value from {headingChannel} yet</> : <>: no heading or course topic is subscribed</>})</>}.</>}</p>}
        {chosen && (
          <div data-testid={`${id}-legend`}>
            <strong>{chosen.label}</strong> <span className="muted">{chosen.detail}</span>
            <div className="legend-bar" />
            <div className="legend-scale"><span>{range ? `${range[0].toPrecision(4)}${unitSuffix}` : "—"}</span><span>{range ? `${range[1].toPrecision(4)}${unitSuffix}` : "—"}</span></div>
          </div>
        )}
        <label>Tile URL (optional)
          <input aria-label="Tile URL" placeholder="https://tile.example/{z}/{x}/{y}.png" value={tileUrl}
            onChange={(e) => { setTileUrl(e.target.value); window.localStorage.setItem(TILE_KEY, e.target.value); }} />
        </label>
        {localTiles && tileUrl !== localTiles && (
          <button type="button" onClick={() => { setTileUrl(localTiles); window.localStorage.setItem(TILE_KEY, localTiles); }}>
            Use the workbench&apos;s tile folder (offline)
          </button>
        )}
        <TileStatus url={tileUrl} count={tiles} />
        <p className="muted">North is up; grid and scale in metres from the first fix.</p>
      </aside>
    </div>
  );
}

export default function MapPanel() {
  const model = useModel();
  const { api } = useServices();
  const drone = useDroneName();
  const { source } = useDroneStream(drone);
  const { lat, lon } = positionSubscribers(model);
  const recordOf = useCallback<RecordSource>((colour) => (lat && lon ? api.track(drone, lat, lon, RECORD_POINTS, colour || undefined)
    : Promise.resolve({ file: null, total: 0, points: [] })), [api, drone, lat, lon]);
  const heading = headingSubscriber(model);
  const choices = model.subscribers.filter((s) => s.topic && s.name !== lat && s.name !== lon && s.name !== heading).map((s) => ({
    channel: s.name, label: s.name, detail: subscriptionLabel(model, s),
    unit: unitLabel(findTopicByName(model, s.topic)?.variable.unit, s.aggregation),
  }));
  // The 3D scene is shared: it follows the choice when the backend runs one (404 otherwise).
  const onColour = (name: string) => { api.setSceneColour(drone, name || null).catch(() => undefined); };
  return (
    <div className="panel-body">
      <TrackMap source={source} lat={lat} lon={lon} choices={choices} onColour={onColour} recordOf={recordOf} headingChannel={heading}
        missing="No subscription delivers a latitude and a longitude: subscribe to them to draw the track." />
    </div>
  );
}
