/**
 * The one place that talks HTTP to the backend. Adds the bearer token (API
 * clients) or the CSRF header of the cookie session (the workbench), turns
 * error responses into `ApiError` carrying the structured body the backend
 * sends ({detail, diagnostics?, current_revision?, denied?}).
 *
 * `fetch` and the base URL are passed in (no globals read at import time), so
 * tests drive it with a fake.
 */
import type { Diagnostic } from "../core/diagnostics";

export interface ErrorBody {
  detail?: unknown;
  diagnostics?: Diagnostic[];
  current_revision?: number;
  denied?: Array<{ part: string; role: string }>;
  [key: string]: unknown;
}

export class ApiError extends Error {
  constructor(
    readonly status: number,
    message: string,
    readonly body: ErrorBody = {},
  ) {
    super(message);
    this.name = "ApiError";
  }

  get isConflict(): boolean { return this.status === 409; }
  get isUnauthorized(): boolean { return this.status === 401; }
}

export interface HttpOptions {
  /** Prefix of every path, e.g. "" (same origin) or "http://127.0.0.1:8000". */
  baseUrl: string;
  fetch: typeof fetch;
  /** Current bearer token (API clients), or null: the workbench's session is an HttpOnly cookie. */
  token: () => string | null;
  /** The cookie session's CSRF token, sent as X-CSRF-Token on every unsafe method. */
  csrf?: () => string | null;
  /** Called on a 401 so the app can return to the login page. */
  onUnauthorized?: () => void;
}

export interface RequestOptions {
  method?: "GET" | "POST" | "PUT" | "PATCH" | "DELETE";
  json?: unknown;
  text?: string;
  query?: Record<string, string | number | undefined>;
  signal?: AbortSignal;
  /** How to read a successful body. */
  as?: "json" | "text" | "blob" | "none";
}

/** A readable message from FastAPI's bodies: a string detail or a list of validation errors. */
export function messageOf(status: number, body: ErrorBody): string {
  const d = body.detail;
  if (typeof d === "string") return d;
  if (Array.isArray(d)) {
    return d.map((e) => {
      const x = e as { loc?: unknown[]; msg?: string };
      return `${(x.loc ?? []).join(".")}: ${x.msg ?? "invalid"}`;
    }).join("; ");
  }
  return `HTTP ${status}`;
}

export class Http {
  constructor(private readonly opts: HttpOptions) {}

  url(path: string, query?: RequestOptions["query"]): string {
    const q = Object.entries(query ?? {})
      .filter(([, v]) => v !== undefined)
      .map(([k, v]) => `${encodeURIComponent(k)}=${encodeURIComponent(String(v))}`)
      .join("&");
    return `${this.opts.baseUrl}${path}${q ? `?${q}` : ""}`;
  }

  async request<T>(path: string, o: RequestOptions = {}): Promise<T> {
    const headers: Record<string, string> = {};
    const token = this.opts.token();
    if (token) headers.Authorization = `Bearer ${token}`;
    const csrf = this.opts.csrf?.();
    if (csrf && (o.method ?? "GET") !== "GET") headers["X-CSRF-Token"] = csrf;
    let body: string | undefined;
    if (o.json !== undefined) {
      headers["Content-Type"] = "application/json";
      body = JSON.stringify(o.json);
    } else if (o.text !== undefined) {
      headers["Content-Type"] = "text/plain; charset=utf-8";
      body = o.text;
    }
    let res: Response;
    try {
      res = await this.opts.fetch(this.url(path, o.query), {
        method: o.method ?? "GET", headers, body, signal: o.signal, credentials: "same-origin",
      });
    } catch (e) {
      if ((e as { name?: string }).name === "AbortError") throw e;
      throw new ApiError(0, `the backend cannot be reached (${(e as Error).message})`);
    }
    if (!res.ok) {
      let errBody: ErrorBody = {};
      try { errBody = (await res.json()) as ErrorBody; } catch { /* not JSON */ }
      if (res.status === 401) this.opts.onUnauthorized?.();
      throw new ApiError(res.status, messageOf(res.status, errBody), errBody);
    }
    switch (o.as ?? "json") {
      case "none": return undefined as T;
      case "text": return (await res.text()) as T;
      case "blob": return (await res.blob()) as T;
      default: return (res.status === 204 ? undefined : await res.json()) as T;
    }
  }
}
