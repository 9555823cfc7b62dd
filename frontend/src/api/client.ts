/**
 * The backend client: one object with a method per endpoint, grouped by
 * resource. UI code calls these (through the services context), never fetch.
 *
 * @example
 *   const api = createApi({ baseUrl: "", fetch: window.fetch.bind(window), token: () => tok });
 *   const { token, user } = await api.login("admin", "secret");
 */
import type { ModdModel } from "../core/model.gen";
import type { Role } from "../core/roles";
import { Http, type FileAnswer, type HttpOptions } from "./http";
import { datasetFile } from "./download";
import type {
  ArchiveFile, ArchiveReplay, ArchiveSeries, BackfillProgress, DatasetFile, DatasetMetadata, DatasetMetadataDoc, DatasetRequest,
  DeployedDiff, Deployment, Fleet, FleetSubscribeRequest, FleetSubscription, Pairing, DynamicReply, DynamicRequest, CredentialsRemade, RecordTrack, Rehearsal, TilesInfo,
  FoxgloveLinks,
  LoginResult, ModelInput, ModelVersion, PlanResult, Project, RunningDrone, User, ValidateResult, Version,
} from "./types";

/**
 * Where the backend serves the viser 3D client, on its own origin (behind the
 * session; the backend proxies viser's HTTP and WebSocket there). The one
 * place the frontend names that path.
 */
export const SCENE_PATH = "/scene/";

export function createApi(opts: HttpOptions) {
  const http = new Http(opts);
  return {
    http,

    // --- auth
    /** A cookie session (HttpOnly, SameSite=Strict; spans tabs): the answer carries the CSRF token, no bearer token. */
    login: (username: string, password: string) =>
      http.request<LoginResult>("/api/auth/login", { method: "POST", json: { username, password, session: "cookie" }, waitTurn: false }),
    logout: () => http.request<void>("/api/auth/logout", { method: "POST", as: "none" }),
    me: () => http.request<User & { csrf?: string | null }>("/api/auth/me"),

    // --- users (admin)
    listUsers: () => http.request<User[]>("/api/users"),
    createUser: (username: string, password: string, roles: Role[]) =>
      http.request<User>("/api/users", { method: "POST", json: { username, password, roles } }),
    /** New roles and/or a new password (which ends the user's sessions). */
    changeUser: (userId: number, change: { roles?: Role[]; password?: string }) =>
      http.request<User>(`/api/users/${userId}`, { method: "PATCH", json: change }),
    deleteUser: (userId: number) => http.request<void>(`/api/users/${userId}`, { method: "DELETE", as: "none" }),

    // --- projects
    listProjects: () => http.request<Project[]>("/api/projects"),
    getProject: (projectId: number) => http.request<Project>(`/api/projects/${projectId}`),
    createProject: (name: string, model: ModdModel | null, message = "created") =>
      http.request<Project>("/api/projects", { method: "POST", json: { name, model: model ? { model } : null, message } }),
    importProject: (name: string, text: string, format: "modd" | "json" = "modd") =>
      http.request<Project>("/api/projects/import", { method: "POST", text, query: { name, format } }),

    // --- models
    readModel: (projectId: number, revision?: number) =>
      http.request<ModelVersion>(`/api/projects/${projectId}/model`, { query: { revision } }),
    saveModel: (projectId: number, model: ModdModel, baseRevision: number, message = "") =>
      http.request<ModelVersion>(`/api/projects/${projectId}/model`, {
        method: "PUT", json: { model, base_revision: baseRevision, message },
      }),
    /** Drones reporting now, with their PubBroker and SubBroker endpoints (defaults for a new project). */
    runningDrones: () => http.request<RunningDrone[]>("/api/running-drones"),
    listVersions: (projectId: number) => http.request<Version[]>(`/api/projects/${projectId}/versions`),
    exportModel: (projectId: number, format: "modd" | "json" | "collector" = "modd", revision?: number) =>
      http.request<string>(`/api/projects/${projectId}/export`, { query: { format, revision }, as: "text" }),
    exportUrl: (projectId: number, format: "modd" | "json" = "modd") =>
      http.url(`/api/projects/${projectId}/export`, { format }),
    /** The .modd text of a model document, saved or not (the text view of unsaved edits). */
    printModel: (model: ModdModel, signal?: AbortSignal) =>
      http.request<string>("/api/print", { method: "POST", json: { model }, as: "text", signal }),
    /** Parse and validate without saving; for text, `model` is the parsed document. */
    validate: (input: ModelInput, signal?: AbortSignal) =>
      http.request<ValidateResult>("/api/validate", { method: "POST", json: input, signal }),

    // --- plan
    /** `calibrate`: an archive the backend holds, "DRONE/NAME.mcap", whose samples size the
     * quantised values (docs/planning.md, "Bounds and estimates"). */
    plan: (input: ModelInput, signal?: AbortSignal, calibrate?: string) =>
      http.request<PlanResult>("/api/plan", { method: "POST", json: input, signal, query: { calibrate } }),

    // --- deploy (operator)
    deploy: (projectId: number, revision?: number) =>
      http.request<Deployment>(`/api/projects/${projectId}/deployments`, { method: "POST", json: { revision: revision ?? null } }),
    listDeployments: (projectId: number) => http.request<Deployment[]>(`/api/projects/${projectId}/deployments`),
    /** A pairing bundle for the project's drone and its one-time code (in the body, never a URL). */
    makePairing: (projectId: number, revision?: number) =>
      http.request<Pairing>(`/api/projects/${projectId}/pairing`, { method: "POST", json: { revision: revision ?? null } }),
    deployedDiff: (projectId: number) => http.request<DeployedDiff>(`/api/projects/${projectId}/deployed-diff`),

    // --- fleet: a project's drones (a campaign's vehicles), deployed and subscribed at once
    fleet: (projectId: number) => http.request<Fleet>(`/api/projects/${projectId}/drones`),
    /** Deploys to the drones given (all when absent), each its own model; one record per drone. A rollback: an older revision, one drone. */
    deployFleet: (projectId: number, drones?: string[], revision?: number) =>
      http.request<Deployment[]>(`/api/projects/${projectId}/fleet/deployments`, {
        method: "POST", json: { revision: revision ?? null, drones: drones ?? null },
      }),
    subscribeFleet: (projectId: number, request: FleetSubscribeRequest) =>
      http.request<FleetSubscription[]>(`/api/projects/${projectId}/fleet/subscriptions`, { method: "POST", json: request }),

    // --- downloads: generated artefacts per role, as a zip
    downloadUrl: (projectId: number, target: string) => http.url(`/api/projects/${projectId}/downloads/${target}`),
    download: (projectId: number, target: string) =>
      http.request<Blob>(`/api/projects/${projectId}/downloads/${target}`, { as: "blob" }),
    /** Foxglove/Lichtblick layout for the live mission (scientist): docs/ecosystem.md. */
    foxgloveLayout: (projectId: number) =>
      http.request<Blob>(`/api/projects/${projectId}/foxglove-layout`, { as: "blob" }),
    /** URLs to open in Foxglove/Lichtblick, each with a ticket good for one connection. */
    foxgloveLinks: () => http.request<FoxgloveLinks>("/api/foxglove/links", { method: "POST" }),
    /** The drone's track since its mission began, from the base-station record (thinned to `points`). */
    track: (drone: string, lat: string, lon: string, points = 2000, colour?: string) =>
      http.request<RecordTrack>(`/api/drones/${encodeURIComponent(drone)}/track?${new URLSearchParams({
        lat, lon, points: String(points), ...(colour ? { colour } : {}) }).toString()}`),
    /** Whether the drone's link is a simulated one that can be cut for a rehearsal, and whether it is cut. */
    rehearsal: (drone: string) => http.request<Rehearsal>(`/api/drones/${encodeURIComponent(drone)}/rehearsal`),
    /** Cuts (true) or restores (false) the simulated link (operator). */
    setRehearsal: (drone: string, cut: boolean) =>
      http.request<Rehearsal>(`/api/drones/${encodeURIComponent(drone)}/rehearsal`, { method: "POST", json: { cut } }),
    /** Whether the workbench serves a tile folder (modd-backend --tiles) and its tile URL. */
    tilesInfo: () => http.request<TilesInfo>("/api/tiles"),
    /** Credential files of the base station made anew after its first start (copies handed out no longer work). */
    credentialsRemade: () => http.request<CredentialsRemade>("/api/credentials/remade"),

    // --- live (scientist): dynamic subscriptions; values come over the stream WebSocket
    addDynamic: (drone: string, body: DynamicRequest) =>
      http.request<DynamicReply>(`/api/drones/${drone}/subscriptions`, { method: "POST", json: body }),
    cancelDynamic: (drone: string, subscriber: string) =>
      http.request<DynamicReply>(`/api/drones/${drone}/subscriptions/${subscriber}`, { method: "DELETE" }),
    // --- backfill: fill what the link missed from the drone's archive
    startBackfill: (drone: string, body: { subscriber: string; gaps?: boolean; from_ns?: number; to_ns?: number; rate_bps?: number }) =>
      http.request<BackfillProgress>(`/api/drones/${drone}/backfill`, { method: "POST", json: body }),
    backfillProgress: (drone: string, id: number) => http.request<BackfillProgress>(`/api/drones/${drone}/backfill/${id}`),
    cancelBackfill: (drone: string, id: number) =>
      http.request<BackfillProgress>(`/api/drones/${drone}/backfill/${id}`, { method: "DELETE" }),
    /** ws(s):// URL of a drone's stream; the session cookie authenticates it (never a token in the URL). */
    streamUrl: (drone: string, origin: string) => {
      const base = (opts.baseUrl || origin).replace(/^http/, "ws");
      return `${base}/api/drones/${drone}/stream`;
    },

    // --- archives
    listArchives: (drone: string) => http.request<ArchiveFile[]>(`/api/drones/${drone}/archives`),
    readArchive: (drone: string, file: string, topic: string, startNs?: number, endNs?: number, maxPoints = 2000) =>
      http.request<ArchiveSeries>(`/api/drones/${drone}/archives/${encodeURIComponent(file)}/series`, {
        query: { topic, start_ns: startNs, end_ns: endNs, max_points: maxPoints },
      }),
    /** The MCAP file itself (a blob: downloads need the bearer token, so no plain link). */
    downloadArchive: (drone: string, file: string) =>
      http.request<Blob>(`/api/drones/${drone}/archives/${encodeURIComponent(file)}`, { as: "blob" }),
    /** The SubBroker's base-station records: every delivered value, live and backfilled. */
    listRecords: (drone: string) => http.request<ArchiveFile[]>(`/api/drones/${drone}/records`),
    /** A base-station record served to Foxglove/Lichtblick (seek, play, pause) on the replay port. */
    replayRecord: (drone: string, file: string, autoplay = false) =>
      http.request<ArchiveReplay>(`/api/drones/${drone}/records/${encodeURIComponent(file)}/replay`, {
        method: "POST", json: { start_ns: null, end_ns: null, autoplay },
      }),
    downloadRecord: (drone: string, file: string) =>
      http.request<Blob>(`/api/drones/${drone}/records/${encodeURIComponent(file)}`, { as: "blob" }),
    /** The archive as a dataset file (`modd dataset`: NetCDF, Parquet, CSV, GeoJSON, GPX), made by the backend. */
    exportDataset: async (drone: string, request: DatasetRequest): Promise<DatasetFile> => {
      const answer = await http.request<FileAnswer>(`/api/drones/${drone}/archives/export`, { method: "POST", json: request, as: "file" });
      return datasetFile(answer.blob, answer.headers, `${drone}-dataset`);
    },
    readDatasetMetadata: (projectId: number) =>
      http.request<DatasetMetadata>(`/api/projects/${projectId}/dataset-metadata`),
    saveDatasetMetadata: (projectId: number, metadata: DatasetMetadataDoc, baseRevision: number) =>
      http.request<DatasetMetadata>(`/api/projects/${projectId}/dataset-metadata`, {
        method: "PUT", json: { base_revision: baseRevision, metadata },
      }),
    archiveCsv: (drone: string, file: string, topic: string, startNs?: number, endNs?: number) =>
      http.request<Blob>(`/api/drones/${drone}/archives/${encodeURIComponent(file)}/csv`, { query: { topic, start_ns: startNs, end_ns: endNs }, as: "blob" }),

    /** Serves the range to Foxglove/Lichtblick (seek, play, pause) on the backend's replay port;
     *  `autoplay`: played once from its start when a viewer subscribes (viewers without playback controls). */
    replayArchive: (drone: string, file: string, startNs?: number, endNs?: number, autoplay = false) =>
      http.request<ArchiveReplay>(`/api/drones/${drone}/archives/${encodeURIComponent(file)}/replay`, {
        method: "POST", json: { start_ns: startNs ?? null, end_ns: endNs ?? null, autoplay },
      }),

    // --- 3D scene (viser), served by the backend
    scene: () => http.request<{ url: string }>("/api/scene"),
    /** Colours the drone's track in the shared 3D scene by a subscriber's values (null: plain). */
    setSceneColour: (drone: string, subscriber: string | null) =>
      http.request<void>(`/api/scene/${drone}/colour`, { method: "PUT", json: { subscriber }, as: "none" }),
  };
}

export type Api = ReturnType<typeof createApi>;
