/**
 * The backend client: one object with a method per endpoint, grouped by
 * resource. UI code calls these (through the services context), never fetch.
 *
 * @example
 *   const api = createApi({ baseUrl: "", fetch: window.fetch.bind(window), token: () => tok });
 *   const { token, user } = await api.login("admin", "secret");
 */
import type { ModdModel } from "../core/model.gen";
import { Http, type HttpOptions } from "./http";
import type {
  LoginResult, ModelInput, ModelVersion, PlanResult, Project, User, ValidateResult, Version,
} from "./types";

export function createApi(opts: HttpOptions) {
  const http = new Http(opts);
  return {
    http,

    // --- auth
    login: (username: string, password: string) =>
      http.request<LoginResult>("/api/auth/login", { method: "POST", json: { username, password } }),
    logout: () => http.request<void>("/api/auth/logout", { method: "POST", as: "none" }),
    me: () => http.request<User>("/api/auth/me"),

    // --- projects
    listProjects: () => http.request<Project[]>("/api/projects"),
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
    listVersions: (projectId: number) => http.request<Version[]>(`/api/projects/${projectId}/versions`),
    exportModel: (projectId: number, format: "modd" | "json" = "modd", revision?: number) =>
      http.request<string>(`/api/projects/${projectId}/export`, { query: { format, revision }, as: "text" }),
    exportUrl: (projectId: number, format: "modd" | "json" = "modd") =>
      http.url(`/api/projects/${projectId}/export`, { format }),
    /** Parse and validate without saving; for text, `model` is the parsed document. */
    validate: (input: ModelInput, signal?: AbortSignal) =>
      http.request<ValidateResult>("/api/validate", { method: "POST", json: input, signal }),

    // --- plan
    plan: (input: ModelInput, signal?: AbortSignal) =>
      http.request<PlanResult>("/api/plan", { method: "POST", json: input, signal }),
  };
}

export type Api = ReturnType<typeof createApi>;
