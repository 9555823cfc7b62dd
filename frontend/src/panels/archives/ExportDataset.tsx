/**
 * Archives → Export dataset: the picked file (or every file) as a dataset
 * scientists open in their tools (`modd dataset` run by the backend): CF
 * NetCDF, Parquet, CSV, GeoJSON or GPX; a time range, topics, and an optional
 * resampling period. The file arrives as a download named by the backend
 * (drone and time span), with the project's saved dataset metadata; the
 * export's notes (dropped glitches, gaps, fills, what a data centre asks for)
 * are shown under the form.
 */
import { useState } from "react";
import { useServices } from "../../app/services";
import { saveBlob } from "../saveBlob";
import { DATASET_FORMATS, type ArchiveFile, type DatasetFormat, type DatasetSource } from "../../api/types";
import type { ModdModel } from "../../core/model.gen";
import { topicLabel } from "../../core/topicLabel";
import { datasetRequest, exportables, type ExportChoice } from "./exportForm";

const FORMAT_WORDS: Record<DatasetFormat, string> = {
  netcdf: "NetCDF (CF trajectory)", parquet: "Parquet", csv: "CSV", geojson: "GeoJSON track", gpx: "GPX track",
};

export function ExportDataset({ model, file, project }: { model: ModdModel; file: ArchiveFile | null; project: number | null }) {
  const { api } = useServices();
  const drone = model.drone.name;
  const [choice, setChoice] = useState<ExportChoice>({ format: "netcdf", from: "", to: "", topics: [], resample: "" });
  const [state, setState] = useState<{ busy?: boolean; error?: string; done?: string; notes?: string[] }>({});
  const topics = exportables(model, file, choice.source);
  const received = choice.source === "received";

  const run = async (e: React.FormEvent) => {
    e.preventDefault();
    const request = datasetRequest(model, choice, file, project);
    if (typeof request === "string") { setState({ error: request }); return; }
    setState({ busy: true });
    try {
      const got = await api.exportDataset(drone, request);
      saveBlob(got.blob, got.name);
      setState({ done: got.name, notes: got.notes });
    } catch (err) {
      setState({ error: (err as Error).message });
    }
  };

  return (
    <form onSubmit={run} className="archive-form" aria-label="Export dataset">
      <strong>Export dataset</strong> {file ? `of ${file.name}` : "of every file"}
      <select aria-label="Dataset source" value={choice.source ?? "archive"}
        title="The samples the drone archived, or the windows the subscribers received (the base-station records)"
        onChange={(e) => setChoice({ ...choice, source: e.target.value as DatasetSource, topics: [] })}>
        <option value="archive">samples archived on board</option>
        <option value="received">windows the subscribers received</option>
      </select>
      <select aria-label="Dataset format" value={choice.format} onChange={(e) => setChoice({ ...choice, format: e.target.value as DatasetFormat })}>
        {DATASET_FORMATS.map((f) => <option key={f} value={f}>{FORMAT_WORDS[f]}</option>)}
      </select>
      <input aria-label="Export from (s after the start)" placeholder="from s" size={6} value={choice.from} disabled={!file}
        onChange={(e) => setChoice({ ...choice, from: e.target.value })} />
      <input aria-label="Export to (s after the start)" placeholder="to s" size={6} value={choice.to} disabled={!file}
        onChange={(e) => setChoice({ ...choice, to: e.target.value })} />
      <input aria-label="Resample period (s)" placeholder="resample s" size={8} value={choice.resample}
        title="Empty: every sample at its own time. A period: the mean of each topic per period (wide form)."
        onChange={(e) => setChoice({ ...choice, resample: e.target.value })} />
      {topics.length > 0 && (
        <select multiple aria-label={received ? "Export subscribers" : "Export topics"} value={choice.topics} size={Math.min(4, topics.length)}
          onChange={(e) => setChoice({ ...choice, topics: [...e.target.selectedOptions].map((o) => o.value) })}>
          {topics.map((t) => <option key={t} value={t}>{received ? t : topicLabel(model, t)}</option>)}
        </select>
      )}
      <button type="submit" disabled={state.busy}>Export</button>
      {state.busy && <span role="status">Exporting…</span>}
      {state.done && <span role="status">Saved {state.done}</span>}
      {state.error && <span className="error" role="alert">{state.error}</span>}
      {state.notes && state.notes.length > 0 && (
        <ul className="export-notes" aria-label="Export notes">
          {state.notes.map((n, i) => <li key={i}>{n}</li>)}
        </ul>
      )}
    </form>
  );
}
