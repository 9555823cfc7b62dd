/**
 * `npm run test:e2e`: the Playwright journey against the real backend.
 * Builds the frontend, starts the backend (a free loopback port, a temporary
 * data dir, a known admin password) and — when the runtime is built — a
 * simulated drone with `modd up --simulate`; runs the journey in headless
 * Chromium at 1280×800; stops what it started, by PID; prints one line
 * "N passed, N failed[, N skipped]" and exits non-zero on any failure.
 */
import { existsSync, mkdtempSync, rmSync, readFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { execFileSync } from "node:child_process";
import { launch } from "./browser.mjs";
import { freePort, start, stop, waitForHttp } from "./processes.mjs";
import { journey } from "./journey.mjs";

const here = dirname(fileURLToPath(import.meta.url));
const frontend = resolve(here, "../..");
const repo = resolve(frontend, "..");
const imagesDir = join(repo, "docs", "images");
const backendBin = join(repo, ".venv", "bin", "modd-backend");
const PASSWORD = "e2e-admin-password";

function fail(message) {
  console.error(`e2e: ${message}`);
  console.log("0 passed, 1 failed");
  process.exit(1);
}

if (!existsSync(backendBin)) fail(`${backendBin} is missing: run scripts/setup.sh`);
if (!existsSync("/usr/bin/chromium") && !process.env.MODD_CHROMIUM) fail("no /usr/bin/chromium: apt-get install chromium (scripts/setup.sh)");

const tmp = mkdtempSync(join(tmpdir(), "modd-e2e-"));
const procs = [];
let passed = 0, failed = 0, skipped = 0;
let browser = null;

async function cleanup() {
  if (browser) await browser.close();
  for (const p of procs.reverse()) await stop(p);
  rmSync(tmp, { recursive: true, force: true });
}
for (const sig of ["SIGINT", "SIGTERM"]) process.on(sig, () => { void cleanup().then(() => process.exit(130)); });

try {
  execFileSync("npx", ["vite", "build", "--logLevel", "error"], { cwd: frontend, stdio: "inherit" });
  const port = await freePort();
  const baseUrl = `http://127.0.0.1:${port}`;
  const backend = start("backend", [
    backendBin, "--host", "127.0.0.1", "--port", String(port), "--data", join(tmp, "data"),
    "--admin-password", PASSWORD, "--frontend", join(frontend, "dist"), "--no-zenoh",
  ], { cwd: repo, logFile: join(tmp, "backend.log") });
  procs.push(backend);
  await waitForHttp(`${baseUrl}/openapi.json`, backend);

  const live = false;
  console.log(`e2e: backend pid ${backend.pid} on ${baseUrl}; live drone: ${live ? "yes" : "no (runtime not wired yet)"}`);
  browser = await launch();
  const page = browser.context.pages()[0] ?? await browser.context.newPage();
  const errors = [];
  page.on("pageerror", (e) => errors.push(e.message));
  const steps = journey({ page, baseUrl, password: PASSWORD, imagesDir, live });
  let broken = null;
  for (const [name, fn] of steps) {
    if (broken) { console.log(`  - ${name}: not run (after "${broken}" failed)`); failed += 1; continue; }
    const t0 = Date.now();
    try {
      await fn();
      if (errors.length) throw new Error(`page error: ${errors.join("; ")}`);
      passed += 1;
      console.log(`  ✓ ${name} (${Date.now() - t0} ms)`);
    } catch (e) {
      failed += 1;
      broken = name;
      console.log(`  ✗ ${name}: ${e.message}`);
      await page.screenshot({ path: join(tmpdir(), "modd-e2e-failure.png") }).catch(() => undefined);
      try { console.log(readFileSync(join(tmp, "backend.log"), "utf8").split("\n").slice(-15).join("\n")); } catch { /* none */ }
    }
  }
  if (!live) { skipped += 1; console.log("  - live values from a simulated drone: skipped (runtime not wired yet)"); }
} catch (e) {
  failed += 1;
  console.error(`e2e: ${e.stack ?? e}`);
} finally {
  await cleanup();
}
console.log(`${passed} passed, ${failed} failed${skipped ? `, ${skipped} skipped` : ""}`);
process.exit(failed ? 1 : 0);
