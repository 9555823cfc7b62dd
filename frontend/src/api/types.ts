/**
 * Bodies of the backend's REST API (backend/src/modd_backend/schemas.py and
 * routers; served as /openapi.json). The model itself is typed by
 * core/model.gen.ts, generated from the metamodel schema.
 */
import type { ModdModel } from "../core/model.gen";
import type { Diagnostic } from "../core/diagnostics";
import type { PlanJson } from "../core/plan";
import type { Role } from "../core/roles";
import type { BackfillQueue } from "../core/contracts.gen";

export interface User {
  id: number;
  username: string;
  roles: Role[];
}

export interface LoginResult {
  /** null for a cookie session (the workbench): the token stays in an HttpOnly cookie. */
  token: string | null;
  /** The cookie session's CSRF token (X-CSRF-Token on unsafe methods). */
  csrf?: string | null;
  user: User;
}

export interface Project {
  id: number;
  name: string;
  created_at: string;
  created_by: string;
  head_revision: number;
}

export interface Version {
  project_id: number;
  revision: number;
  valid: boolean;
  author: string;
  message: string;
  created_at: string;
}

export interface ModelVersion extends Version {
  model: ModdModel;
  diagnostics: Diagnostic[];
}

export interface ValidateResult {
  ok: boolean;
  model: ModdModel | null;
  diagnostics: Diagnostic[];
}

export interface PlanResult {
  ok: boolean;
  plan: PlanJson | null;
  diagnostics: Diagnostic[];
  elapsed_ms: number;
}

export type ModelInput = { model: ModdModel } | { text: string; format?: "modd" | "json" };

/**
 * A pairing bundle just made (POST /api/projects/{id}/pairing, operator): the file's
 * text (saved as `filename`), its one-time code (shown once, never stored), the base
 * station's key fingerprint the drone pins, and where the station keeps the link key.
 */
export interface Pairing {
  drone: string;
  revision: number;
  filename: string;
  bundle: string;
  code: string;
  fingerprint: string;
  expires_at: string;
  link_key_file: string;
}

export interface Deployment {
  id: number;
  project_id: number;
  revision: number;
  drone: string;
  requested_by: string;
  requested_at: string;
  finished_at: string | null;
  /** acked (the PubBroker took the config) or failed (`error` says why). */
  status: string;
  reply: Record<string, unknown> | null;
  error: string | null;
}

/** One drone of a project (backend routers/fleet.py): a campaign's vehicle, or the project's one drone. */
export interface FleetDrone {
  name: string;
  description: string | null;
  channel: string | null;
  pub_broker: { endpoint: { host: string; port: number } };
  sub_broker: { endpoint: { host: string; port: number } };
  /** This project's last deployment to it. */
  deployment: Deployment | null;
  /** Its last status document when it reported lately (link, station, last_data_ns, sensors, ...), else null. */
  status: Record<string, unknown> | null;
}

/** A project's drones, and its shared radio channels' members. */
export interface Fleet {
  campaign: string | null;
  drones: FleetDrone[];
  channels: Record<string, string[]>;
}

/** A subscription to `sensor.variable` of every drone (or the listed ones), in one step. */
export interface FleetSubscribeRequest {
  variable: string;
  period_s: string;
  aggregation: string;
  subscriber?: string;
  drones?: string[];
}

/** One drone's answer to a fleet subscription. */
export interface FleetSubscription extends DynamicReply { drone: string; topic: string }

/** A drone reporting its status now, with the link ends of the model last deployed to it. */
export interface RunningDrone {
  drone: string;
  project_id: number | null;
  revision: number | null;
  pub_broker: { host: string; port: number } | null;
  sub_broker: { host: string; port: number } | null;
}

export interface DeployedDiff {
  drone: string;
  head_revision: number;
  deployed: Deployment | null;
  same_project: boolean;
  changes: Array<{ op: string; pointer: string; before?: unknown; after?: unknown }>;
}

export interface DynamicRequest {
  topic: string;
  period_s: string;
  aggregation: string;
  subscriber?: string;
}

/** The SubBroker's answer: ACCEPTED (with key), NOT_AVAILABLE (with reason), CANCELLED, ERROR, NO_REPLY. */
export interface DynamicReply {
  status: string;
  reason?: string | null;
  subscriber?: string | null;
  key?: string | null;
  stream?: string | null;
  derived_from?: string | null;
  factor?: number | null;
}

/** A backfill's progress (backend routers/backfill.py; docs/subbroker.md, "Backfill"). */
export interface BackfillProgress {
  status: string;
  reason?: string | null;
  id?: number | null;
  subscriber?: string | null;
  windows: number;
  windows_done: number;
  windows_total: number;
  duplicates: number;
  bytes: number;
  rate_bps: number;
  seconds: number;
  bytes_per_s: number;
  seconds_left?: number | null;
  /** The SubBroker's view of its backfill queue (a running job's answer only). */
  queue?: BackfillQueue | null;
}

/** An MCAP archive of a drone (backend routers/archives.py). */
export interface ArchiveFile {
  name: string;
  size: number;
  /** False while the PubBroker still writes it. */
  complete: boolean;
  start_ns: number | null;
  end_ns: number | null;
  topics: Array<{ topic: string; messages: number }>;
}

/** Viewer URLs with single-use tickets (backend routers/foxglove.py); null: not served. */
/** GET /api/drones/{drone}/track: fixes [t (s since the epoch), lat, lon, colour value?] of the newest base-station record, thinned; `total` before thinning. */
export interface RecordTrack { file: string | null; total: number; points: Array<[number, number, number] | [number, number, number, number | null]> }

/** GET/POST /api/drones/{drone}/rehearsal: a simulated link (modd up --simulate) that can be cut, and whether it is. */
export interface Rehearsal { available: boolean; cut: boolean }

/** GET /api/tiles: the workbench's tile folder, when it serves one. */
export interface TilesInfo { available: boolean; url: string | null }

/** GET /api/credentials/remade: credential files made anew, with when (UTC ISO 8601). */
export interface CredentialsRemade { remade: Array<{ file: string; at: string }> }

export interface FoxgloveLinks {
  live: string | null;
  replay: string | null;
  ticket_ttl_s: number;
}

/** A replay served to Foxglove/Lichtblick (backend routers/archives.py); `url` carries a single-use ticket. */
export interface ArchiveReplay {
  url: string;
  drone: string;
  file: string;
  start_ns: number;
  end_ns: number;
  messages: number;
  topics: string[];
  started_by: string;
  /** Plays once from the start when a viewer subscribes (viewers without playback controls). */
  autoplay: boolean;
}

/** A topic over a time range; `points` are [log time ns, value], min/max-reduced to at most max_points. */
/** The dataset formats of `modd dataset` (backend routers/archives.py ExportIn). */
export const DATASET_FORMATS = ["netcdf", "parquet", "csv", "geojson", "gpx"] as const;
export type DatasetFormat = (typeof DATASET_FORMATS)[number];

/** What a dataset holds: the samples archived on board, or the windows the subscribers received (base-station records). */
export type DatasetSource = "archive" | "received";

/** POST /api/drones/<drone>/archives/export: the model the archive was made with, and what to keep. */
export interface DatasetRequest {
  model: ModdModel;
  format: DatasetFormat;
  source?: DatasetSource;
  files?: string[];
  start_ns?: number | null;
  end_ns?: number | null;
  topics?: string[] | null;
  resample_s?: number | null;
  /** The project whose saved dataset metadata the file carries. */
  project?: number | null;
}

/** A project's dataset metadata (ACDD/IOOS attribute names, `platform`, `instruments`, `qc`: a dataset.yaml). */
export type DatasetMetadataDoc = Record<string, unknown>;

export interface DatasetMetadata {
  project_id: number;
  revision: number; // 0: none saved yet
  metadata: DatasetMetadataDoc;
  author: string | null;
  created_at: string | null;
  /** What ACDD 1.3 / IOOS 1.2 ask for that it does not give. */
  missing: string[];
}

/** An exported dataset: the file, the name the backend gave it and its notes. */
export interface DatasetFile {
  blob: Blob;
  name: string;
  notes: string[];
}

export interface ArchiveSeries {
  topic: string;
  total: number;
  reduced: boolean;
  points: Array<[number, unknown]>;
}
