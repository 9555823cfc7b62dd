/**
 * Map: the drone's track in 2D, drawn on a canvas (no WebGL), in local
 * metres from its first fix with a grid, a scale bar and north up; each fix
 * coloured by a chosen subscription, with its legend. Tiles are optional (a
 * tile URL such as https://tile.openstreetmap.org/{z}/{x}/{y}.png, kept in
 * this browser): offline, the plain local plot is the map.
 *
 * The positions come from the subscriptions whose topics are a latitude and
 * a longitude (core/track), over the workbench's shared stream, or from a
 * source handed in (archive playback). The colour choice also colours the
 * backend's 3D scene, when it runs one.
 */
import { useEffect, useRef, useState } from "react";
import { positionSubscribers, trackPoints, valueRange, type TrackPoint } from "../../core/track";
import { unitLabel } from "../../core/chartData";
import { findTopicByName } from "../../core/query";
import { useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { useDroneStream } from "../../app/useDroneStream";
import type { DataSource } from "../../dataSources/types";
import { drawMap } from "./drawMap";

const TILE_KEY = "modd.map.tileUrl";

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

export function TrackMap({ source }: { source: DataSource }) {
  const model = useModel();
  const { api } = useServices();
  const { lat, lon } = positionSubscribers(model);
  const others = model.subscribers.filter((s) => s.topic && s.name !== lat && s.name !== lon);
  const [colour, setColour] = useState(() => others[0]?.name ?? "");
  const [tileUrl, setTileUrl] = useState(() => window.localStorage.getItem(TILE_KEY) ?? "");
  const points = useTrack(source, lat, lon, colour);
  const canvas = useRef<HTMLCanvasElement>(null);
  const range = valueRange(points);
  const sub = model.subscribers.find((s) => s.name === colour);
  const unit = sub ? unitLabel(findTopicByName(model, sub.topic)?.variable.unit, sub.aggregation) : "";
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
    if (el) el.dataset.trackPx = JSON.stringify(drawMap(el, points, range, { tileUrl, onTile: () => setRedraw((n) => n + 1) }));
  }, [points, range?.[0], range?.[1], tileUrl, redraw]); // eslint-disable-line react-hooks/exhaustive-deps

  const chooseColour = (name: string) => {
    setColour(name);
    // The 3D scene is shared: it follows the choice when the backend runs one (404 otherwise).
    api.setSceneColour(model.drone.name, name || null).catch(() => undefined);
  };

  return (
    <div className="map-panel">
      <canvas ref={canvas} className="map-canvas" role="img" data-testid="map-canvas" data-points={points.length}
        aria-label={`Track of ${model.drone.name}: ${points.length} fixes${sub ? `, coloured by ${sub.name}` : ""}`} />
      <aside className="map-legend" aria-label="Map legend">
        <label>Colour by{" "}
          <select aria-label="Colour by" value={colour} onChange={(e) => chooseColour(e.target.value)}>
            <option value="">(plain)</option>
            {others.map((s) => <option key={s.name} value={s.name}>{s.name}: {s.topic} {s.aggregation}</option>)}
          </select>
        </label>
        {!lat || !lon ? <p className="muted" role="status">No subscription delivers a latitude and a longitude: subscribe to them to draw the track.</p>
          : <p className="muted" role="status">{points.length} fixes from {lat} and {lon}.</p>}
        {sub && (
          <div data-testid="map-legend">
            <strong>{sub.name}</strong> <span className="muted">{sub.topic} {sub.aggregation}{unit ? ` (${unit})` : ""}</span>
            <div className="legend-bar" />
            <div className="legend-scale"><span>{range ? range[0].toPrecision(4) : "—"}</span><span>{range ? range[1].toPrecision(4) : "—"}</span></div>
          </div>
        )}
        <label>Tile URL (optional)
          <input aria-label="Tile URL" placeholder="https://tile.example/{z}/{x}/{y}.png" value={tileUrl}
            onChange={(e) => { setTileUrl(e.target.value); window.localStorage.setItem(TILE_KEY, e.target.value); }} />
        </label>
        <p className="muted">North is up; grid and scale in metres from the first fix.</p>
      </aside>
    </div>
  );
}

export default function MapPanel() {
  const drone = useModel().drone.name;
  const { source } = useDroneStream(drone);
  return <div className="panel-body"><TrackMap source={source} /></div>;
}
