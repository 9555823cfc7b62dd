/**
 * The Export dataset form's rules, apart from the component: what request a
 * filled form makes (the backend names the download: drone and time span).
 *
 *   datasetRequest(model, { format: "netcdf", from: "10", to: "", topics: [], resample: "" }, file)
 *   // { model, format: "netcdf", files: [file.name], start_ns: file.start_ns + 10e9, ... }
 */
import type { ArchiveFile, DatasetFormat, DatasetRequest, DatasetSource } from "../../api/types";
import type { ModdModel } from "../../core/model.gen";

export interface ExportChoice {
  format: DatasetFormat;
  /** "received": the windows the subscribers received (every base-station record of the drone). */
  source?: DatasetSource;
  from: string; // seconds after the file's first message ("" = its start)
  to: string;
  topics: string[]; // none chosen = every topic
  resample: string; // seconds; "" = every raw sample at its own time
}

/** What a form asks for (with the project whose saved dataset metadata the file carries);
 *  an error text instead when a field cannot be read. */
export function datasetRequest(model: ModdModel, c: ExportChoice, file: ArchiveFile | null,
  project: number | null = null): DatasetRequest | string {
  const seconds = (text: string, what: string): number | null | string => {
    if (text.trim() === "") return null;
    const n = Number(text);
    return Number.isFinite(n) && n >= 0 ? n : `${what}: a number of seconds, please`;
  };
  const from = seconds(c.from, "from"), to = seconds(c.to, "to"), resample = seconds(c.resample, "resample");
  for (const v of [from, to, resample]) if (typeof v === "string") return v;
  if (resample === 0) return "resample: a period greater than zero";
  const base = file?.start_ns ?? null;
  const at = (s: number | null) => (s === null || base === null ? null : base + Math.round(s * 1e9));
  const received = c.source === "received";
  return {
    model, format: c.format, ...(received ? { source: "received" as const } : {}),
    // the records are the drone's (the range, on the same drone clock, picks the mission)
    files: file && !received ? [file.name] : [],
    start_ns: at(from as number | null), end_ns: at(to as number | null),
    topics: c.topics.length ? c.topics : null, resample_s: resample as number | null,
    ...(project !== null ? { project } : {}),
  };
}

/** What can be chosen to export: the file's topics, or the model's subscribers for received windows. */
export function exportables(model: ModdModel, file: ArchiveFile | null, source: DatasetSource | undefined): string[] {
  if (source === "received") return (model.subscribers ?? []).map((s) => s.name);
  return file?.topics.map((t) => t.topic) ?? [];
}
