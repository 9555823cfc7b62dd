/**
 * The live plan's latency after an edit, as a person sees it (`make bench`):
 * a real `modd-backend` on loopback (no drone), headless Chromium at
 * 1280×800, scenario 1 from its template; `--edits N` times the scientist
 * sets sub_1's period (2.0 ↔ 4.0 s) in the inspector and presses Enter, and
 * the time from the key press to the Plan panel showing the new hyperperiod
 * is taken. Prints each figure's median, p90 and max; asserts nothing.
 *
 *     cd frontend && node tests/bench/live-plan-latency.mjs --edits 20
 */
import { existsSync, mkdtempSync, rmSync } from "node:fs";
import { execFileSync } from "node:child_process";
import { tmpdir } from "node:os";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { launch } from "../e2e/browser.mjs";
import { freePort, start, stop, waitForHttp } from "../e2e/processes.mjs";

const here = dirname(fileURLToPath(import.meta.url));
const frontend = resolve(here, "../..");
const repo = resolve(frontend, "..");
const arg = (name, dflt) => { const i = process.argv.indexOf(`--${name}`); return i > 0 ? Number(process.argv[i + 1]) : dflt; };
const EDITS = arg("edits", 20);
const PASSWORD = "bench-admin-password";

const quantile = (xs, q) => { const s = [...xs].sort((a, b) => a - b); return s[Math.min(s.length - 1, Math.floor(q * s.length))]; };

const tmp = mkdtempSync(join(tmpdir(), "modd-bench-plan-"));
let backend = null;
let browser = null;
try {
  if (!existsSync(join(frontend, "dist", "index.html")) || process.env.MODD_BENCH_BUILD !== "0") {
    execFileSync("npx", ["vite", "build", "--logLevel", "error"], { cwd: frontend, stdio: "inherit" });
  }
  const port = await freePort();
  const base = `http://127.0.0.1:${port}`;
  backend = start("backend", [join(repo, ".venv", "bin", "modd-backend"), "--host", "127.0.0.1", "--port", String(port),
    "--data", join(tmp, "data"), "--frontend", join(frontend, "dist"), "--no-zenoh",
    "--archives", join(tmp, "archives"), "--records", join(tmp, "records")],
  { cwd: repo, logFile: join(tmp, "backend.log"), env: { MODD_ADMIN_PASSWORD: PASSWORD } });
  await waitForHttp(`${base}/openapi.json`, backend);
  browser = await launch();
  const page = browser.context.pages()[0] ?? await browser.context.newPage();
  await page.goto(base);
  await page.getByLabel("User name").fill("admin");
  await page.getByLabel("Password").fill(PASSWORD);
  await page.getByRole("button", { name: "Log in" }).click();
  await page.getByLabel("Project name").fill("latency");
  await page.getByLabel("Start from").selectOption({ index: 1 }); // scenario 1 of the paper
  await page.getByRole("button", { name: "Create" }).click();
  await page.getByRole("tab", { name: "Scientist", exact: true }).click();
  const hyper = page.getByTestId("hyperperiod");
  await hyper.waitFor({ timeout: 120000 }); // the first plan starts the planner's workers
  await page.locator('.react-flow__node[data-id="sub:sub_1"]').click();
  const period = page.getByRole("region", { name: "Inspector" }).locator('[data-field="periodS"] input').first();
  const times = [];
  for (let i = 0; i <= EDITS; i++) {
    const value = i % 2 === 0 ? "4.0" : "2.0";
    await period.fill(value);
    const t0 = await page.evaluate(() => performance.now());
    await period.press("Enter");
    const t1 = await page.waitForFunction((v) => {
      const el = document.querySelector('[data-testid="hyperperiod"]');
      return el && el.textContent?.includes(`${v} s`) && !el.closest(".plan-stale") ? performance.now() : null;
    }, value, { polling: "raf", timeout: 30000 }).then((h) => h.jsonValue());
    if (i > 0) times.push(t1 - t0); // the first is a warm-up
  }
  console.log(`live plan after an edit, ${EDITS} edits (Enter in the inspector → the Plan panel shows the new hyperperiod):`);
  console.log(`  median ${quantile(times, 0.5).toFixed(0)} ms, p90 ${quantile(times, 0.9).toFixed(0)} ms, max ${Math.max(...times).toFixed(0)} ms`);
} finally {
  if (browser) await browser.close();
  if (backend) await stop(backend, 8000);
  rmSync(tmp, { recursive: true, force: true });
}
