/**
 * Processes the journey starts and stops itself, by PID (each in its own
 * process group, so children go too): the backend, and `modd up` for the
 * simulated drone. Only loopback addresses.
 */
import { spawn } from "node:child_process";
import { createServer } from "node:net";
import { openSync } from "node:fs";

/** A free TCP port on 127.0.0.1. */
export function freePort() {
  return new Promise((resolve, reject) => {
    const srv = createServer();
    srv.once("error", reject);
    srv.listen(0, "127.0.0.1", () => {
      const { port } = srv.address();
      srv.close(() => resolve(port));
    });
  });
}

/** Starts `argv` detached in its own process group, output to `logFile`. */
export function start(name, argv, { cwd, logFile, env } = {}) {
  const out = openSync(logFile, "a");
  const child = spawn(argv[0], argv.slice(1), { cwd, env: { ...process.env, ...env }, detached: true, stdio: ["ignore", out, out] });
  const proc = { name, pid: child.pid, child, exited: null };
  child.on("exit", (code, signal) => { proc.exited = { code, signal }; });
  return proc;
}

/** SIGTERM to the process group, SIGKILL after `graceMs`. */
export async function stop(proc, graceMs = 8000) {
  if (!proc || proc.exited) return;
  try { process.kill(-proc.pid, "SIGTERM"); } catch { return; }
  const t0 = Date.now();
  while (!proc.exited && Date.now() - t0 < graceMs) await sleep(100);
  if (!proc.exited) {
    try { process.kill(-proc.pid, "SIGKILL"); } catch { /* gone */ }
    await sleep(200);
  }
}

export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/** Polls `url` until it answers 2xx, the process exits, or `timeoutMs` passes. */
export async function waitForHttp(url, proc, timeoutMs = 60000) {
  const t0 = Date.now();
  while (Date.now() - t0 < timeoutMs) {
    if (proc.exited) throw new Error(`${proc.name} exited (${JSON.stringify(proc.exited)}) before answering ${url}`);
    try {
      const r = await fetch(url);
      if (r.ok) return;
    } catch { /* not up yet */ }
    await sleep(250);
  }
  throw new Error(`${proc.name} did not answer ${url} within ${timeoutMs} ms`);
}
