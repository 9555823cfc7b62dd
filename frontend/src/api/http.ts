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

/** A download with its headers (`as: "file"`): the backend names it (Content-Disposition). */
export interface FileAnswer {
  blob: Blob;
  headers: Headers;
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
  /** How to wait for a turn (tests pass a fake clock); default setTimeout. */
  sleep?: (ms: number, signal?: AbortSignal) => Promise<void>;
}

/**
 * Heavy requests (archive series, CSV, deploy) beyond the backend's slots are
 * refused before any work with 429/503 and Retry-After (backend guards.py):
 * such a request waits its turn here, a Retry-After of at most
 * `MAX_TURN_WAIT_S` at a time and `MAX_TURNS` times, instead of telling the
 * user to click again.
 */
export const MAX_TURN_WAIT_S = 5;
export const MAX_TURNS = 30;

function sleepFor(ms: number, signal?: AbortSignal): Promise<void> {
  return new Promise((resolve, reject) => {
    const t = setTimeout(resolve, ms);
    signal?.addEventListener("abort", () => { clearTimeout(t); reject(new DOMException("aborted", "AbortError")); }, { once: true });
  });
}

/** Seconds to wait before asking again, or null when this answer is not "wait your turn". */
export function turnWait(res: Pick<Response, "status" | "headers">): number | null {
  if (res.status !== 429 && res.status !== 503) return null;
  const s = Number(res.headers.get("Retry-After"));
  return Number.isFinite(s) && s > 0 && s <= MAX_TURN_WAIT_S ? s : null;
}

export interface RequestOptions {
  method?: "GET" | "POST" | "PUT" | "PATCH" | "DELETE";
  json?: unknown;
  text?: string;
  query?: Record<string, string | number | undefined>;
  signal?: AbortSignal;
  /** How to read a successful body. */
  as?: "json" | "text" | "blob" | "file" | "none";
  /** Wait for a turn when the backend says it is busy (default true; a login does not). */
  waitTurn?: boolean;
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
    const init: RequestInit = { method: o.method ?? "GET", headers, body, signal: o.signal, credentials: "same-origin" };
    let res = await this.send(path, o, init);
    for (let turn = 0; turn < MAX_TURNS && o.waitTurn !== false; turn++) {
      const wait = turnWait(res);
      if (wait === null) break;
      await (this.opts.sleep ?? sleepFor)(wait * 1000, o.signal);
      res = await this.send(path, o, init);
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
      case "file": return { blob: await res.blob(), headers: res.headers } as T;
      default: return (res.status === 204 ? undefined : await res.json()) as T;
    }
  }

  private async send(path: string, o: RequestOptions, init: RequestInit): Promise<Response> {
    try {
      return await this.opts.fetch(this.url(path, o.query), init);
    } catch (e) {
      if ((e as { name?: string }).name === "AbortError") throw e;
      throw new ApiError(0, `the backend cannot be reached (${(e as Error).message})`);
    }
  }
}
