/**
 * Map: the drone's track in 2D, drawn on a canvas (no WebGL), in local
 * metres from its first fix with a grid, a scale bar and north up; each fix
 * coloured by a chosen subscription, with its legend. Tiles are optional (a
 * tile URL such as https://tile.openstreetmap.org/{z}/{x}/{y}.png, kept in
 * this browser; the service must allow its origin, `--tile-origin`):
 * offline, the plain local plot is the map.
 *
 * The positions come from the subscriptions whose topics are a latitude and
 * a longitude (core/track), over the workbench's shared stream; archive
 * playback hands in its own source and topics (TrackMap), and the map shows
 * the track up to the playback cursor. The colour choice also colours the
 * backend's 3D scene, when it runs one.
 */
import { subscriptionLabel } from "../../core/topicLabel";
import { useEffect, useRef, useState } from "react";
import { positionSubscribers, trackPoints, valueRange, type TrackPoint } from "../../core/track";
import { unitLabel } from "../../core/chartData";
import { findTopicByName } from "../../core/query";
import { useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { useDroneStream } from "../../app/useDroneStream";
import type { DataSource } from "../../dataSources/types";
import { drawMap, tileOrigin, tileUrlProblem, type TileCount } from "./drawMap";
import { defaultColour } from "./marker";

const TILE_KEY = "modd.map.tileUrl";

/** A channel of the source the track can be coloured by. */
export interface ColourChoice { channel: string; label: string; detail: string; unit: string }

function useTrack(source: DataSource, lat: string | null, lon: string | null, colour: string): TrackPoint[] {
  const [points, setPoints] = useState<TrackPoint[]>([]);
  useEffect(() => {
    if (!lat || !lon) { setPoints([]); return; }
    let frame = 0;
    const build = () => setPoints(trackPoints(source.history(lat), source.history(lon), colour ? source.history(colour) : []));
    const later = () => { if (!frame) frame = requestAnimationFrame(() => { frame = 0; build(); }); };
    build();
    const offs = [lat, lon, colour].filter(Boolean).map((c) => source.subscribe(c, later));
    return () => { offs.forEach((o) => o()); cancelAnimationFrame(frame); };
  }, [source, lat, lon, colour]);
  return points;
}

function TileStatus({ url, count }: { url: string; count: TileCount }) {
  const problem = tileUrlProblem(url);
  if (!url) return null;
  if (problem) return <p className="error" role="alert" data-testid="tile-status">Tiles off: {problem}.</p>;
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
}

export function TrackMap({ source, lat, lon, choices, onColour, id = "map", missing }: TrackMapProps) {
  const drone = useModel().drone.name;
  const [colour, setColour] = useState(() => defaultColour(choices));
  const [tileUrl, setTileUrl] = useState(() => window.localStorage.getItem(TILE_KEY) ?? "");
  const [tiles, setTiles] = useState<TileCount>({ asked: 0, drawn: 0, failed: 0 });
  const points = useTrack(source, lat, lon, colour);
  const canvas = useRef<HTMLCanvasElement>(null);
  const range = valueRange(points);
  const chosen = choices.find((c) => c.channel === colour);
  const [redraw, setRedraw] = useState(0);

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
    const drawn = drawMap(el, points, range, { tileUrl, onTile: () => setRedraw((n) => n + 1) });
    el.dataset.trackPx = JSON.stringify(drawn.px);
    el.dataset.origin = points.length ? `${points[0].lat},${points[0].lon}` : "";
    el.dataset.heading = drawn.heading === null ? "" : drawn.heading.toFixed(0);
    setTiles((t) => (t.asked === drawn.tiles.asked && t.drawn === drawn.tiles.drawn && t.failed === drawn.tiles.failed ? t : drawn.tiles));
  }, [points, range?.[0], range?.[1], tileUrl, redraw]); // eslint-disable-line react-hooks/exhaustive-deps

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
          : <p className="muted" role="status">{points.length} fixes from {lat} and {lon}.</p>}
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
        <TileStatus url={tileUrl} count={tiles} />
        <p className="muted">North is up; grid and scale in metres from the first fix.</p>
      </aside>
    </div>
  );
}

export default function MapPanel() {
  const model = useModel();
  const { api } = useServices();
  const { source } = useDroneStream(model.drone.name);
  const { lat, lon } = positionSubscribers(model);
  const choices = model.subscribers.filter((s) => s.topic && s.name !== lat && s.name !== lon).map((s) => ({
    channel: s.name, label: s.name, detail: subscriptionLabel(model, s),
    unit: unitLabel(findTopicByName(model, s.topic)?.variable.unit, s.aggregation),
  }));
  // The 3D scene is shared: it follows the choice when the backend runs one (404 otherwise).
  const onColour = (name: string) => { api.setSceneColour(model.drone.name, name || null).catch(() => undefined); };
  return (
    <div className="panel-body">
      <TrackMap source={source} lat={lat} lon={lon} choices={choices} onColour={onColour}
        missing="No subscription delivers a latitude and a longitude: subscribe to them to draw the track." />
    </div>
  );
}
