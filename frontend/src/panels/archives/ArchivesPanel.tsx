/**
 * Archives: the drone's MCAP files (from the backend, which reads them with
 * the official mcap reader); plot a topic over a time range (min/max-reduced
 * by the backend for plotting); download the file or the range as CSV; play
 * a range back through the monitor's charts (Playback: seek, play, pause);
 * export the archive as a dataset (ExportDataset: NetCDF, Parquet, CSV, GeoJSON, GPX).
 */
import { useEffect, useRef, useState } from "react";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { useEditor, useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { usePanelData, LoadState } from "../usePanelData";
import { BaseRecords } from "./BaseRecords";
import { saveBlob } from "../saveBlob";
import type { ArchiveFile, ArchiveReplay, ArchiveSeries } from "../../api/types";
import { Playback } from "./Playback";
import { ExportDataset } from "./ExportDataset";
import { DatasetMetadataForm } from "./DatasetMetadataForm";
import { topicLabel } from "../../core/topicLabel";

function SeriesChart({ series, name }: { series: ArchiveSeries; name: string }) {
  const host = useRef<HTMLDivElement>(null);
  useEffect(() => {
    const el = host.current;
    if (!el) return;
    const pts = series.points.filter(([, v]) => typeof v === "number" || typeof v === "boolean");
    const plot = new uPlot({
      width: Math.max(el.clientWidth, 200), height: 180, scales: { x: { time: true } }, legend: { show: false },
      series: [{}, { label: name, stroke: "#0f766e", width: 1 }],
    }, [pts.map(([t]) => t / 1e9), pts.map(([, v]) => Number(v))], el);
    return () => plot.destroy();
  }, [series, name]);
  return (
    <figure className="live-chart">
      <figcaption>{name}: {series.total} samples{series.reduced ? `, reduced to ${series.points.length} points` : ""}</figcaption>
      <div ref={host} className="chart-host" aria-label={`Archived ${series.topic}`} />
    </figure>
  );
}

const seconds = (ns: number | null) => (ns === null ? "—" : new Date(ns / 1e6).toLocaleString());

export default function ArchivesPanel() {
  const { api } = useServices();
  const model = useModel();
  const drone = model.drone.name;
  const project = useEditor((s) => s.project?.id ?? null);
  const [files, reload] = usePanelData(() => api.listArchives(drone), [drone]);
  const [file, setFile] = useState<ArchiveFile | null>(null);
  const [topic, setTopic] = useState("");
  const [range, setRange] = useState({ from: "", to: "" });
  const [series, setSeries] = useState<{ data?: ArchiveSeries; error?: string; busy?: boolean }>({});
  const chosenTopic = topic || file?.topics[0]?.topic || "";
  // The range is typed in seconds after the file's first message.
  const bound = (s: string) => (s && file?.start_ns != null ? file.start_ns + Math.round(Number(s) * 1e9) : undefined);

  const plot = async (e: React.FormEvent) => {
    e.preventDefault();
    if (!file) return;
    setSeries({ busy: true });
    try {
      setSeries({ data: await api.readArchive(drone, file.name, chosenTopic, bound(range.from), bound(range.to)) });
    } catch (err) {
      setSeries({ error: (err as Error).message });
    }
  };
  const [replay, setReplay] = useState<ArchiveReplay | null>(null);
  // Lichtblick's WebSocket player has no playback controls: the server then plays by itself.
  const [autoplay, setAutoplay] = useState(false);
  const startReplay = async () => {
    if (!file) return;
    setSeries({ busy: true });
    try {
      setReplay(await api.replayArchive(drone, file.name, bound(range.from), bound(range.to), autoplay));
      setSeries({});
    } catch (err) {
      setSeries({ error: (err as Error).message });
    }
  };
  const download = async (blob: Promise<Blob>, name: string) => {
    try { saveBlob(await blob, name); } catch (err) { setSeries({ error: (err as Error).message }); }
  };

  return (
    <div className="panel-body archives-panel">
      <LoadState value={files} what="archives" />
      {files.state !== "ready" && files.state !== "loading" && <button onClick={reload}>Retry</button>}
      {files.state === "ready" && (
        <div className="archives-grid">
          <div>
            <button onClick={reload}>Refresh</button>
            <table className="history-table" aria-label="Archive files">
              <thead><tr><th>File</th><th>Size</th><th>From</th><th>To</th><th /></tr></thead>
              <tbody>
                {files.data.length === 0 && <tr><td colSpan={5} className="muted">No archive yet for {drone}.</td></tr>}
                {files.data.map((f) => (
                  <tr key={f.name} className={file?.name === f.name ? "picked" : ""}>
                    <td><button className="link" onClick={() => { setFile(f); setTopic(""); }}>{f.name}</button>{f.complete ? "" : " (being written)"}</td>
                    <td>{(f.size / 1024).toFixed(1)} KiB</td><td>{seconds(f.start_ns)}</td><td>{seconds(f.end_ns)}</td>
                    <td><button className="link" onClick={() => void download(api.downloadArchive(drone, f.name), f.name)}>download</button></td>
                  </tr>
                ))}
              </tbody>
            </table>
            <BaseRecords drone={drone} autoplay={autoplay} />
          </div>
          <div>
            <form onSubmit={plot} className="archive-form" aria-label="Plot an archived topic">
              <select aria-label="Topic" value={chosenTopic} onChange={(e) => setTopic(e.target.value)} disabled={!file}>
                {file?.topics.map((t) => <option key={t.topic} value={t.topic}>{topicLabel(model, t.topic)} · {t.messages} messages</option>)}
              </select>
              <input aria-label="From (s after the start)" placeholder="from s" value={range.from} onChange={(e) => setRange({ ...range, from: e.target.value })} size={6} />
              <input aria-label="To (s after the start)" placeholder="to s" value={range.to} onChange={(e) => setRange({ ...range, to: e.target.value })} size={6} />
              <button type="submit" disabled={!file}>Plot</button>
              <button type="button" disabled={!file} onClick={() => file && void download(api.archiveCsv(drone, file.name, chosenTopic, bound(range.from), bound(range.to)), `${file.name}-${chosenTopic}.csv`)}>CSV</button>
              <button type="button" disabled={!file} onClick={() => void startReplay()} title="Serve this range to Foxglove or Lichtblick: seek, play, pause">Replay in Foxglove</button>
              <label title="For viewers without playback controls (Lichtblick): the replay plays once from its start when the viewer subscribes">
                <input type="checkbox" checked={autoplay} onChange={(e) => setAutoplay(e.target.checked)} /> play at once
              </label>
              {series.busy && <span role="status">Reading…</span>}
              {series.error && <span className="error" role="alert">{series.error}</span>}
            </form>
            {project !== null && <DatasetMetadataForm model={model} project={project} />}
            <ExportDataset model={model} file={file} project={project} />
            {replay && (
              <p role="status" aria-label="Foxglove replay">
                Replay of {replay.file} ({replay.messages} messages, {replay.topics.length} topics): in Foxglove or Lichtblick,
                Open connection → Foxglove WebSocket → <code>{replay.url}</code>
                {replay.autoplay && " (plays from the start when the viewer subscribes)"}
              </p>
            )}
            {!file && <p className="muted">Pick a file to plot one of its topics.</p>}
            {series.data && <SeriesChart series={series.data} name={topicLabel(model, series.data.topic)} />}
          </div>
          {file && <Playback key={file.name} file={file} bound={bound} />}
        </div>
      )}
    </div>
  );
}
