import { describe, expect, it, vi } from "vitest";
import { ApiError, Http } from "./http";
import { createApi } from "./client";

function fakeFetch(status: number, body: unknown, contentType = "application/json") {
  return vi.fn(async (_url: string, _init?: RequestInit) =>
    new Response(typeof body === "string" ? body : JSON.stringify(body), { status, headers: { "Content-Type": contentType } }),
  );
}

describe("Http", () => {
  it("sends the bearer token and JSON, builds queries", async () => {
    const f = fakeFetch(200, { ok: true });
    const http = new Http({ baseUrl: "http://127.0.0.1:1", fetch: f as unknown as typeof fetch, token: () => "tok" });
    await http.request("/api/x", { method: "POST", json: { a: 1 }, query: { q: "a b", none: undefined } });
    const [url, init] = f.mock.calls[0];
    expect(url).toBe("http://127.0.0.1:1/api/x?q=a%20b");
    expect((init!.headers as Record<string, string>).Authorization).toBe("Bearer tok");
    expect(init!.body).toBe('{"a":1}');
  });

  it("turns error bodies into ApiError with the structured body", async () => {
    const f = fakeFetch(409, { detail: "the model was saved meanwhile", current_revision: 4 });
    const http = new Http({ baseUrl: "", fetch: f as unknown as typeof fetch, token: () => null });
    const err = await http.request("/api/x").catch((e: ApiError) => e) as ApiError;
    expect(err).toBeInstanceOf(ApiError);
    expect(err.isConflict).toBe(true);
    expect(err.message).toMatch(/saved meanwhile/);
    expect(err.body.current_revision).toBe(4);
  });

  it("reads FastAPI validation errors and reports 401", async () => {
    const onUnauthorized = vi.fn();
    const f = fakeFetch(401, { detail: [{ loc: ["body", "name"], msg: "too short" }] });
    const http = new Http({ baseUrl: "", fetch: f as unknown as typeof fetch, token: () => null, onUnauthorized });
    const err = await http.request("/api/x").catch((e: ApiError) => e) as ApiError;
    expect(err.message).toBe("body.name: too short");
    expect(onUnauthorized).toHaveBeenCalledOnce();
  });

  it("says when the backend cannot be reached", async () => {
    const f = vi.fn(async () => { throw new TypeError("Failed to fetch"); });
    const http = new Http({ baseUrl: "", fetch: f as unknown as typeof fetch, token: () => null });
    const err = await http.request("/api/x").catch((e: ApiError) => e) as ApiError;
    expect(err.status).toBe(0);
    expect(err.message).toMatch(/cannot be reached/);
  });
});

describe("createApi", () => {
  it("saves with the base revision", async () => {
    const f = fakeFetch(200, { revision: 2 });
    const api = createApi({ baseUrl: "", fetch: f as unknown as typeof fetch, token: () => "t" });
    await api.saveModel(3, { schemaVersion: "1.0" } as never, 1, "msg");
    const [url, init] = f.mock.calls[0];
    expect(url).toBe("/api/projects/3/model");
    expect(init!.method).toBe("PUT");
    expect(JSON.parse(init!.body as string)).toEqual({ model: { schemaVersion: "1.0" }, base_revision: 1, message: "msg" });
  });
});

describe("cookie session", () => {
  it("asks for a cookie, sends the CSRF header on unsafe methods only, never a token in the stream URL", async () => {
    const f = fakeFetch(200, { token: null, csrf: "c", user: { id: 1, username: "a", roles: [] } });
    const api = createApi({ baseUrl: "", fetch: f as unknown as typeof fetch, token: () => null, csrf: () => "c" });
    await api.login("a", "pw");
    const [, login] = f.mock.calls[0];
    expect(JSON.parse(login!.body as string)).toEqual({ username: "a", password: "pw", session: "cookie" });
    expect(login!.credentials).toBe("same-origin");
    expect((login!.headers as Record<string, string>)["X-CSRF-Token"]).toBe("c");
    expect((login!.headers as Record<string, string>).Authorization).toBeUndefined();
    await api.listProjects();
    expect((f.mock.calls[1][1]!.headers as Record<string, string>)["X-CSRF-Token"]).toBeUndefined();
    expect(api.streamUrl("usv", "http://h:1")).toBe("ws://h:1/api/drones/usv/stream");
  });

  it("waits its turn when the backend's heavy slots are taken, instead of failing", async () => {
    let calls = 0;
    const f = vi.fn(async () => {
      calls += 1;
      if (calls <= 2) {
        return new Response(JSON.stringify({ detail: "at most 2 heavy requests at once per user (CSV, series, deploy); retry shortly" }),
          { status: calls === 1 ? 429 : 503, headers: { "Content-Type": "application/json", "Retry-After": "1" } });
      }
      return new Response(JSON.stringify({ points: [[1, 2]] }), { status: 200, headers: { "Content-Type": "application/json" } });
    });
    const sleep = vi.fn(async () => {});
    const http = new Http({ baseUrl: "", fetch: f as unknown as typeof fetch, token: () => null, sleep });
    const got = await http.request<{ points: number[][] }>("/api/drones/usv/archives/a.mcap/series");
    expect(got.points).toEqual([[1, 2]]);
    expect(f).toHaveBeenCalledTimes(3);
    expect(sleep.mock.calls.map((c) => (c as unknown[])[0])).toEqual([1000, 1000]);
  });

  it("does not wait on a long Retry-After, nor for a login", async () => {
    const sleep = vi.fn(async () => {});
    const busy = (after: string) => vi.fn(async () => new Response(JSON.stringify({ detail: "too many failed logins; try again later" }),
      { status: 429, headers: { "Content-Type": "application/json", "Retry-After": after } }));
    const long = busy("60");
    const http = new Http({ baseUrl: "", fetch: long as unknown as typeof fetch, token: () => null, sleep });
    expect((await http.request("/api/x").catch((e: ApiError) => e) as ApiError).status).toBe(429);
    const login = busy("1");
    const http2 = new Http({ baseUrl: "", fetch: login as unknown as typeof fetch, token: () => null, sleep });
    await http2.request("/api/auth/login", { method: "POST", json: {}, waitTurn: false }).catch(() => null);
    expect(long).toHaveBeenCalledOnce();
    expect(login).toHaveBeenCalledOnce();
    expect(sleep).not.toHaveBeenCalled();
  });
});
