/**
 * Plays back a time range of an archive file through the monitor's charts:
 * pick topics, load the range (the backend reads it with the official mcap
 * reader, at most `MAX_POINTS` points per topic), then seek, play and pause;
 * the charts show what was recorded up to the cursor, and zoom like live ones.
 * When the file holds a latitude and a longitude, they are read too and the
 * map beside the charts (above them in a narrow panel) shows the track up to
 * the cursor, coloured by a picked topic; it stays in view while the charts
 * scroll. A file with several position sources (a GPS and an NMEA GNSS, say)
 * lets the user pick which track to draw, the one with the most fixes first.
 * Loading brings the playback into view.
 */
import { useEffect, useMemo, useRef, useState } from "react";
import { PlaybackSource, archiveSamples } from "../../dataSources/PlaybackSource";
import { DEFAULT_WINDOW, unitLabel, type ViewWindow } from "../../core/chartData";
import { findTopicByName } from "../../core/query";
import { topicLabel } from "../../core/topicLabel";
import { useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import type { ArchiveFile } from "../../api/types";
import { LiveChart } from "../monitor/LiveChart";
import { positionPairs, type PositionPair } from "../../core/track";
import { TrackMap } from "../map/MapPanel";

const MAX_POINTS = 5000;
const RATES = [1, 10, 60];

function usePlayback(source: PlaybackSource | null): { t: number; playing: boolean } {
  const [state, setState] = useState({ t: source?.cursor ?? 0, playing: false });
  useEffect(() => {
    if (!source) return;
    setState({ t: source.cursor, playing: source.playing });
    const off = source.onCursor((t, playing) => setState({ t, playing }));
    return () => { off(); source.pause(); };
  }, [source]);
  return state;
}

export function Playback({ file, bound }: { file: ArchiveFile; bound: (s: string) => number | undefined }) {
  const { api } = useServices();
  const model = useModel();
  const drone = model.drone.name;
  const [picked, setPicked] = useState<string[]>(() => file.topics.slice(0, 2).map((t) => t.topic));
  const [range, setRange] = useState({ from: "", to: "" });
  const [loaded, setLoaded] = useState<{ source?: PlaybackSource; error?: string; busy?: boolean }>({});
  const source = loaded.source ?? null;
  const { t, playing } = usePlayback(source);
  const [rate, setRate] = useState(10);
  const [charts, setCharts] = useState<string[][]>([]);
  const [win, setWin] = useState<ViewWindow>(DEFAULT_WINDOW);
  const pairs = useMemo(() => positionPairs(file.topics), [file.topics]);
  const [chosen, setChosen] = useState(0);
  const position: PositionPair | null = pairs[chosen] ?? pairs[0] ?? null;
  // the track of the last load (another choice is read at the next load)
  const [track, setTrack] = useState<PositionPair | null>(null);
  const controls = useRef<HTMLDivElement>(null);
  // Loaded: the controls, the map and the first charts come into view together.
  useEffect(() => { if (source) controls.current?.scrollIntoView({ block: "start" }); }, [source]);
  const whole: ViewWindow = useMemo(() => (source ? { follow: false, from: source.start, to: Math.max(source.end, source.start + 1) } : DEFAULT_WINDOW), [source]);

  const load = async (e: React.FormEvent) => {
    e.preventDefault();
    setLoaded({ busy: true });
    try {
      const wanted = [...new Set([...picked, ...(position ? [position.lat, position.lon] : [])])];
      // Two reads at a time: series reads are heavy routes, limited per user (backend settings: heavy_per_user).
      const all: Awaited<ReturnType<typeof api.readArchive>>[] = [];
      for (let i = 0; i < wanted.length; i += 2) {
        all.push(...await Promise.all(wanted.slice(i, i + 2).map((topic) =>
          api.readArchive(drone, file.name, topic, bound(range.from), bound(range.to), MAX_POINTS))));
      }
      const src = new PlaybackSource(Object.fromEntries(all.map((s) => [s.topic, archiveSamples(s.points)])));
      setCharts(picked.map((p) => [p]));
      setTrack(position);
      setWin({ follow: false, from: src.start, to: Math.max(src.end, src.start + 1) });
      setLoaded({ source: src });
    } catch (err) {
      setLoaded({ error: (err as Error).message });
    }
  };
  const describe = (topic: string) => ({ channel: topic, title: topicLabel(model, topic), label: "archived", unit: unitLabel(findTopicByName(model, topic)?.variable.unit) });
  const toggle = (topic: string) => setPicked((p) => (p.includes(topic) ? p.filter((x) => x !== topic) : [...p, topic]));

  return (
    <section className="playback-section" aria-label="Archive playback">
      <form onSubmit={load} className="archive-form" aria-label="Play back an archive range">
        <strong>Play back</strong>
        {file.topics.map((tp) => (
          <label key={tp.topic}><input type="checkbox" checked={picked.includes(tp.topic)} onChange={() => toggle(tp.topic)} />{topicLabel(model, tp.topic)}</label>
        ))}
        {pairs.length > 1 && (
          <label>Track from{" "}
            <select aria-label="Track from" value={chosen} onChange={(e) => setChosen(Number(e.target.value))}>
              {pairs.map((p, i) => <option key={`${p.lat}+${p.lon}`} value={i}>{p.lat} + {p.lon.split(".").pop()} ({p.fixes} fixes)</option>)}
            </select>
          </label>
        )}
        <input aria-label="Playback from (s after the start)" placeholder="from s" value={range.from} onChange={(e) => setRange({ ...range, from: e.target.value })} size={6} />
        <input aria-label="Playback to (s after the start)" placeholder="to s" value={range.to} onChange={(e) => setRange({ ...range, to: e.target.value })} size={6} />
        <button type="submit" disabled={picked.length === 0 || loaded.busy}>Load for playback</button>
        {loaded.busy && <span role="status">Reading…</span>}
        {loaded.error && <span className="error" role="alert">{loaded.error}</span>}
      </form>
      {source && (
        <>
          <div ref={controls} className="playback" role="group" aria-label="Playback controls">
            <button onClick={() => (playing ? source.pause() : source.play(rate))}>{playing ? "Pause" : "Play"}</button>
            <input type="range" aria-label="Seek" min={source.start} max={source.end} step={(source.end - source.start) / 1000 || 1}
              value={t} onChange={(e) => source.seek(Number(e.target.value))} />
            <select aria-label="Speed" value={rate} onChange={(e) => { setRate(Number(e.target.value)); source.rate = Number(e.target.value); }}>
              {RATES.map((r) => <option key={r} value={r}>{r}×</option>)}
            </select>
            <span data-testid="playback-time">{(t - source.start).toFixed(1)} s of {(source.end - source.start).toFixed(1)} s · {new Date(t * 1000).toLocaleTimeString()}{playing ? " · playing" : " · paused"}</span>
            <button onClick={() => setWin(whole)}>Whole range</button>
          </div>
          <div className={`playback-body${track ? " with-map" : ""}`}>
            {track && (
              <div className="playback-map" aria-label="Track up to the playback time">
                <TrackMap key={`${file.name}:${charts.flat().join(",")}`} source={source} lat={track.lat} lon={track.lon} id="playback-map"
                  choices={charts.flat().filter((c) => c !== track.lat && c !== track.lon).map((c) => ({ ...describe(c), detail: "archived", label: topicLabel(model, c) }))}
                  missing="" />
              </div>
            )}
            <div className="charts">
              {charts.map((chart, i) => (
                <LiveChart key={chart.join("+")} source={source} series={chart.map(describe)} window={win} syncKey="playback" marker={t} now={t}
                  onZoom={(from, to) => setWin({ follow: false, from, to })}
                  addable={charts.flat().filter((c) => !chart.includes(c))}
                  onAdd={(c) => setCharts((cs) => cs.map((x, j) => (j === i ? [...x, c] : x.filter((y) => y !== c))).filter((x) => x.length))}
                  onRemove={(c) => setCharts((cs) => [...cs.map((x) => x.filter((y) => y !== c)).filter((x) => x.length), [c]])} />
              ))}
            </div>
          </div>
        </>
      )}
    </section>
  );
}
