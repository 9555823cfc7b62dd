/**
 * Archives: the drone's MCAP files; plot a topic over a time range (reduced by
 * the backend for plotting); download the file.
 */
import { useEffect, useRef, useState } from "react";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { listTopics } from "../../core/query";
import { useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { usePanelData, LoadState } from "../usePanelData";
import type { ArchiveSeries } from "../../api/types";

function SeriesChart({ series }: { series: ArchiveSeries }) {
  const host = useRef<HTMLDivElement>(null);
  useEffect(() => {
    const el = host.current;
    if (!el) return;
    const plot = new uPlot({
      width: Math.max(el.clientWidth, 200), height: 180, scales: { x: { time: true } }, legend: { show: false },
      series: [{}, { label: series.topic, stroke: "#0f766e", width: 1 }],
    }, [series.t, series.value], el);
    return () => plot.destroy();
  }, [series]);
  return <div ref={host} className="chart-host" aria-label={`Archived ${series.topic}`} />;
}

export default function ArchivesPanel() {
  const { api } = useServices();
  const model = useModel();
  const drone = model.drone.name;
  const [files, reload] = usePanelData(() => api.listArchives(drone), [drone]);
  const topics = listTopics(model);
  const [file, setFile] = useState("");
  const [topic, setTopic] = useState("");
  const [range, setRange] = useState({ from: "", to: "" });
  const [series, setSeries] = useState<{ data?: ArchiveSeries; error?: string; busy?: boolean }>({});

  const plot = async (e: React.FormEvent) => {
    e.preventDefault();
    setSeries({ busy: true });
    try {
      const from = range.from ? Number(range.from) : undefined;
      const to = range.to ? Number(range.to) : undefined;
      setSeries({ data: await api.readArchive(drone, file, topic || topics[0]?.name || "", from, to) });
    } catch (err) {
      setSeries({ error: (err as Error).message });
    }
  };

  return (
    <div className="panel-body archives-panel">
      <LoadState value={files} what="archives" />
      {files.state !== "ready" && <button onClick={reload}>Retry</button>}
      {files.state === "ready" && (
        <div className="archives-grid">
          <ul className="archive-list" aria-label="Archive files">
            {files.data.length === 0 && <li className="muted">No archive yet.</li>}
            {files.data.map((f) => (
              <li key={f.name} className={file === f.name ? "picked" : ""}>
                <button className="link" onClick={() => setFile(f.name)}>{f.name}</button>
                {f.size !== undefined && <span className="muted"> {(f.size / 1024).toFixed(1)} KiB</span>}
                {" "}<a href={api.archiveUrl(drone, f.name)} download>download</a>
              </li>
            ))}
          </ul>
          <form onSubmit={plot} className="archive-form" aria-label="Plot an archived topic">
            <select aria-label="Topic" value={topic || topics[0]?.name || ""} onChange={(e) => setTopic(e.target.value)}>
              {topics.map((t) => <option key={t.id}>{t.name}</option>)}
            </select>
            <input aria-label="From (s since epoch)" placeholder="from" value={range.from} onChange={(e) => setRange({ ...range, from: e.target.value })} size={10} />
            <input aria-label="To (s since epoch)" placeholder="to" value={range.to} onChange={(e) => setRange({ ...range, to: e.target.value })} size={10} />
            <button type="submit" disabled={!file}>Plot</button>
            {series.busy && <span role="status">Reading…</span>}
            {series.error && <span className="error" role="alert">{series.error}</span>}
          </form>
          {series.data && <SeriesChart series={series.data} />}
        </div>
      )}
    </div>
  );
}
