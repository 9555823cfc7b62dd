/**
 * `npm run test:e2e`: the Playwright journey against the real backend.
 * Builds the frontend, starts the backend (a free loopback port, a temporary
 * data dir, a known admin password) and — when the runtime is built — a
 * simulated drone with `modd up --simulate`; runs the journey in headless
 * Chromium at 1280×800; stops what it started, by PID; prints one line
 * "N passed, N failed" and exits non-zero on any failure.
 */
import { existsSync, mkdirSync, mkdtempSync, rmSync, readFileSync, writeFileSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { execFileSync } from "node:child_process";
import { launch } from "./browser.mjs";
import { freePort, sleep, start, stop, waitForHttp } from "./processes.mjs";
import { journey } from "./journey.mjs";
import { collaboration } from "./collab.mjs";
import { views } from "./views.mjs";
import { radio } from "./radio.mjs";
import { instrumentParts, instruments } from "./instruments.mjs";
import { startTileServer } from "./tiles.mjs";
import { metadataJourney } from "./metadata.mjs";
import { credentialsJourney } from "./credentials.mjs";
import { pairing } from "./pairing.mjs";
import { fleetJourney, startFleet } from "./fleet.mjs";
import { alertsJourney } from "./alerts.mjs";

const here = dirname(fileURLToPath(import.meta.url));
const frontend = resolve(here, "../..");
const repo = resolve(frontend, "..");
// Screenshots go to a temporary folder: a test never writes into the work tree.
// `make screenshots` (MODD_SCREENSHOTS=docs/images) refreshes the user guide's pictures.
const imagesDir = process.env.MODD_SCREENSHOTS
  ? resolve(repo, process.env.MODD_SCREENSHOTS)
  : mkdtempSync(join(tmpdir(), "modd-e2e-shots-"));
const bin = join(repo, ".venv", "bin");
const backendBin = join(bin, "modd-backend");
const pubbrokerBin = process.env.MODD_PUBBROKER ?? join(repo, "build", "bin", "modd-pubbroker");
const simulatorBin = join(bin, "modd-sim");
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
let passed = 0, failed = 0;
let browser = null;
const cleanups = []; // extra browsers the steps open

/** Instruments on pseudo-terminals of this run (pty_instruments.py, stopped with the others); their folder. */
async function feedInstruments() {
  const dir = join(tmp, "instruments");
  mkdirSync(dir, { recursive: true });
  const feeder = start("instruments", [join(bin, "python"), join(here, "pty_instruments.py"), dir],
    { cwd: repo, logFile: join(tmp, "instruments.log") });
  procs.push(feeder);
  for (let i = 0; i < 100 && !(existsSync(join(dir, "gps2")) && existsSync(join(dir, "ctd2"))); i += 1) {
    if (feeder.exited) throw new Error(`the instruments' feeder exited: ${readFileSync(join(tmp, "instruments.log"), "utf8")}`);
    await sleep(100);
  }
  return dir;
}

async function cleanup() {
  for (const c of cleanups) await c();
  if (browser) await browser.close();
  // `modd up` stops its own children (their own sessions) on SIGTERM, within 10 s.
  for (const p of procs.reverse()) await stop(p, p.name.startsWith("modd up") ? 15000 : 8000);
  rmSync(tmp, { recursive: true, force: true });
}
for (const sig of ["SIGINT", "SIGTERM"]) process.on(sig, () => { void cleanup().then(() => process.exit(130)); });

try {
  execFileSync("npx", ["vite", "build", "--logLevel", "error"], { cwd: frontend, stdio: "inherit" });
  const [port, zport, pubPort, subPort] = [await freePort(), await freePort(), await freePort(), await freePort()];
  const [foxglovePort, replayPort] = [await freePort(), await freePort()];
  const baseUrl = `http://127.0.0.1:${port}`;
  const zenoh = `tcp/127.0.0.1:${zport}`;
  const creds = join(tmp, "credentials");
  // The simulated drone: PubBroker + SubBroker (+ simulated sensors) of scenario 1,
  // as the journey builds it, on free loopback ports. Needs the C++ build.
  const drone = existsSync(pubbrokerBin);
  const liveValues = drone && existsSync(simulatorBin);
  // MODD_E2E_ONLY=pairing: no `modd up`; the pairing steps start their own base station
  // (a second backend and, once paired, a SubBroker) and the paired drone (pairing.mjs).
  const pairingOnly = process.env.MODD_E2E_ONLY === "pairing";
  // MODD_E2E_ONLY=fleet: no `modd up` of scenario 1; three simulated drones of a campaign
  // (fleet.mjs), brought up by one `modd up` of the campaign, the backend joined to its router.
  const fleetOnly = process.env.MODD_E2E_ONLY === "fleet";
  let fleet = null;
  const pairedModel = { ...scenario1(await freePort(), await freePort()) };
  pairedModel.pubBroker = { ...pairedModel.pubBroker, logPath: join(tmp, "paired-archive"), ingress: { unixSocket: join(tmp, "paired-ingress.sock") } };
  if (drone && fleetOnly) {
    execFileSync(join(bin, "python"), ["-c", "import sys; from modd.zenoh_auth import CredentialStore; "
      + "CredentialStore(sys.argv[1]).ensure()", creds], { cwd: repo, stdio: "inherit" });
    fleet = await startFleet({ repo, bin, tmp, creds, pubbrokerBin, procs });
  } else if (drone && !pairingOnly) {
    const model = scenario1(pubPort, subPort);
    // The plug-and-play instruments (instruments.mjs): simulated on pseudo-terminals, read by modd-sensors.
    const instr = instrumentParts();
    model.drone.sensors.push(...instr.sensors);
    model.publishers.push(instr.publisher);
    writeFileSync(join(tmp, "scenario1.json"), JSON.stringify(model));
    // The SubBroker's zenoh router authenticates its clients (docs/security.md): the
    // credentials and the deploy key, made here so that the backend has them at once.
    execFileSync(join(bin, "python"), ["-c", "import sys; from modd.zenoh_auth import CredentialStore; "
      + "CredentialStore(sys.argv[1]).ensure()", creds], { cwd: repo, stdio: "inherit" });
    const up = start("modd up", [join(bin, "modd"), "up", join(tmp, "scenario1.json"), "--workdir", join(tmp, "drone"),
      "--credentials", creds, "--zenoh-listen", zenoh, ...(liveValues ? ["--simulate"] : [])], { cwd: repo, logFile: join(tmp, "drone.log"),
      env: { MODD_PUBBROKER: pubbrokerBin, MODD_SIM_FAULTS: join(tmp, "sim-faults.json") } });
    procs.push(up);
    // `modd up` writes the PubBroker's archive to <workdir>/archive: the backend reads it as a
    // one-drone archive directory (a drone folder symlinked out of the archive directory is refused).
  }
  // A map tile server on loopback; the backend allows its origin for images (--tile-origin).
  const tiles = await startTileServer();
  mkdirSync(join(tmp, "tiles"));
  cleanups.push(tiles.close);
  const backend = start("backend", [
    backendBin, "--host", "127.0.0.1", "--port", String(port), "--data", join(tmp, "data"),
    "--frontend", join(frontend, "dist"),
    "--foxglove-port", String(foxglovePort), "--foxglove-replay-port", String(replayPort),
    "--tile-origin", tiles.origin,
    // a tile folder the backend serves (offline basemap); views.mjs writes its tiles where the track is
    "--tiles", join(tmp, "tiles"),
    "--archives", drone ? join(tmp, "drone", "archive") : join(tmp, "archives"),
    "--records", drone ? join(tmp, "drone", "records") : join(tmp, "records"),
    // a peer (it listens too) joins the fleet's router(s)
    ...(fleet ? [...fleet.endpoints.flatMap((e) => ["--zenoh-connect", e]), "--zenoh-listen", `tcp/127.0.0.1:${await freePort()}`] : []),
    ...(drone ? [...(fleet ? [] : ["--zenoh-connect", zenoh]), "--zenoh-credentials", join(creds, "backend.cred"),
      "--deploy-key", join(creds, "deploy.key")] : ["--no-zenoh"]),
  ], { cwd: repo, logFile: join(tmp, "backend.log"), env: { MODD_ADMIN_PASSWORD: PASSWORD } });
  procs.push(backend);
  await waitForHttp(`${baseUrl}/openapi.json`, backend);
  console.log(`e2e: backend pid ${backend.pid} on ${baseUrl}; drone: ${drone ? `modd up pid ${procs[0].pid}` : `no (${pubbrokerBin} not built)`}; simulated values: ${liveValues ? "yes" : "no (no modd-sim)"}`);
  await warmPlanner(baseUrl);
  browser = await launch();
  const page = browser.context.pages()[0] ?? await browser.context.newPage();
  const errors = [];
  // The 3D scene's own CSP refuses eval (docs/security.md, "3D scene"): viser's Gaussian-splat
  // sorter asks for it and is refused; MoDD draws no splats, so that refusal is expected.
  const expected = (m) => m.includes("'unsafe-eval' is not an allowed source of script");
  page.on("pageerror", (e) => { if (!expected(e.message)) errors.push(e.message); });
  // MODD_E2E_ONLY=collab: only the collaboration steps (frontend/tests/e2e/collab.mjs);
  // MODD_E2E_ONLY=views: the journey and views.mjs, without them;
  // MODD_E2E_ONLY=instruments: only the instruments' steps (instruments.mjs).
  const only = process.env.MODD_E2E_ONLY;
  // MODD_E2E_ONLY=radio: log in, then only the radio budget steps (radio.mjs).
  // The radio steps put a test flight's archive where the backend reads archives (--archives).
  const radioSteps = () => radio({ page, baseUrl, password: PASSWORD, archiveDir: drone ? join(tmp, "drone", "archive") : join(tmp, "archives") });
  // MODD_E2E_ONLY=metadata: log in, then only the dataset metadata steps (metadata.mjs).
  const metadataSteps = () => metadataJourney({ page, imagesDir, model: scenario1(pubPort, subPort), liveValues, baseUrl, password: PASSWORD,
    faultsFile: join(tmp, "sim-faults.json") });
  // MODD_E2E_ONLY=credentials: log in, then only the re-created credential file's step (credentials.mjs).
  const credentialsSteps = () => credentialsJourney({ page, imagesDir, model: scenario1(pubPort, subPort), credsDir: creds,
    droneDir: join(tmp, "drone"), dronePid: drone ? procs[0].pid : null });
  // MODD_E2E_ONLY=pairing: log in, then the pairing steps (pairing.mjs).
  // The station is started by the pairing's first step: a base station of its own (its backend,
  // zenoh endpoint and credentials), not the one `modd up` serves drone usv on.
  const station = {};
  const pairingSteps = () => [
    ["pairing: a second base station (backend, zenoh endpoint, credentials) for a fresh drone", async () => {
      Object.assign(station, await pairingStation());
      await loginStep(page, station.baseUrl)[1]();
    }],
    ...pairing({ page, imagesDir, bin, tmp, model: pairedModel, pubbrokerBin, station, procs }),
  ];
  // MODD_E2E_ONLY=alerts: log in, then only the alert steps (alerts.mjs, issue 45).
  const alertSteps = () => alertsJourney({ page, model: scenario1(pubPort, subPort), liveValues, imagesDir });
  const steps = only === "fleet" ? [loginStep(page, baseUrl), ...(fleet ? fleetJourney({ page, imagesDir, fleet }) : [])] : only === "alerts" ? [loginStep(page, baseUrl), ...alertSteps()] : only === "credentials" ? [loginStep(page, baseUrl), ...credentialsSteps()] : only === "pairing" ? pairingSteps() : only === "metadata" ? [loginStep(page, baseUrl), ...metadataSteps()] : only === "radio" ? [journey({ page, baseUrl, password: PASSWORD, imagesDir, ports: { pub: pubPort, sub: subPort }, drone, liveValues })[0], ...radioSteps()] : [
    ...(only === "collab" || only === "instruments" ? [] : journey({ page, baseUrl, password: PASSWORD, imagesDir, ports: { pub: pubPort, sub: subPort }, drone, liveValues })),
    // Issue 20's "seeing what changed" and "plots and the map" (views.mjs), on the journey's project.
    ...(only === "collab" || only === "instruments" ? [] : views({ page, baseUrl, imagesDir, drone, liveValues, dronePid: drone ? procs[0].pid : null, ports: { pub: pubPort, sub: subPort },
      archiveDir: join(tmp, "drone", "archive"),
      survey: surveyModel(pubPort, subPort), tiles, tileDir: join(tmp, "tiles") })),
    ...(only === "views" || only === "instruments" ? [] : collaboration({ page, baseUrl, password: PASSWORD, imagesDir, ports: { pub: pubPort, sub: subPort }, drone, onCleanup: (fn) => cleanups.push(fn) })),
    ...(only === "views" || only === "collab" || only === "instruments" ? [] : radioSteps()),
    ...(only === "views" || only === "collab" || only === "instruments" ? [] : metadataSteps()),
    ...(only === "views" || only === "collab" || only === "instruments" ? [] : alertSteps()),
    // Issue 32: the four plug-and-play instruments declared, deployed and watched (last: it deploys its own model).
    ...(only === "instruments" ? [loginStep(page, baseUrl)] : []),
    ...(only === "views" || only === "collab" ? [] : instruments({ page, ports: { pub: pubPort, sub: subPort }, drone, liveValues, feedInstruments })),
    // Issue 42: a deleted credential file announced (it restarts the SubBroker: after the others on it).
    ...(only ? [] : credentialsSteps()),
    // Issue 43: pairing a freshly installed drone with a base station of its own (pairing.mjs;
    // last: the page then works on that station).
    ...(only === "views" || only === "collab" || only === "instruments" || !drone ? [] : pairingSteps()),
  ];
  let broken = null;
  // MODD_E2E_KEEP_GOING=1: the later steps still run after a failure (to see them locally; they
  // may fail for the failed step's sake). By default they are not run.
  const keepGoing = process.env.MODD_E2E_KEEP_GOING === "1";
  for (const [name, fn] of steps) {
    if (broken && !keepGoing) { console.log(`  - ${name}: not run (after "${broken}" failed)`); failed += 1; continue; }
    const t0 = Date.now();
    try {
      await fn();
      if (errors.length) throw new Error(`page error: ${errors.join("; ")}`);
      passed += 1;
      console.log(`  ✓ ${name} (${Date.now() - t0} ms)`);
    } catch (e) {
      failed += 1;
      broken = name;
      errors.length = 0;
      console.log(`  ✗ ${name}: ${e.message}`);
      await page.screenshot({ path: join(tmpdir(), "modd-e2e-failure.png") }).catch(() => undefined);
    }
  }
  // `make test` builds the PubBroker and installs modd-sim: their absence is a
  // broken set-up, so these phases fail rather than pass unnoticed.
  if (!drone) { failed += 1; console.log(`  ✗ deploy acked by a drone: ${pubbrokerBin} is not built (make build)`); }
  if (!liveValues) { failed += 1; console.log("  ✗ live values in a chart: no simulated sensors (modd-sim is not installed)"); }
  if (failed) {
    for (const log of ["backend.log", "drone.log"]) {
      try { console.log(`--- ${log}\n${readFileSync(join(tmp, log), "utf8").split("\n").slice(-20).join("\n")}`); } catch { /* none */ }
    }
  }
} catch (e) {
  failed += 1;
  console.error(`e2e: ${e.stack ?? e}`);
} finally {
  await cleanup();
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);

/**
 * A second base station for the pairing steps: a backend with its own data folder, a
 * free port, and the zenoh endpoint and credentials the paired drone's SubBroker will
 * serve (pairing.mjs starts that SubBroker once the drone is paired).
 */
async function pairingStation() {
  const [port, zport, fox, replay] = [await freePort(), await freePort(), await freePort(), await freePort()];
  const station = { baseUrl: `http://127.0.0.1:${port}`, zenoh: `tcp/127.0.0.1:${zport}`,
    creds: join(tmp, "station2", "credentials"), dataDir: join(tmp, "station2", "data") };
  for (const d of ["archives", "records"]) mkdirSync(join(tmp, "station2", d), { recursive: true });
  execFileSync(join(bin, "python"), ["-c", "import sys; from modd.zenoh_auth import CredentialStore; "
    + "CredentialStore(sys.argv[1]).ensure()", station.creds], { cwd: repo, stdio: "inherit" });
  const backend = start("backend (pairing station)", [
    backendBin, "--host", "127.0.0.1", "--port", String(port), "--data", station.dataDir,
    "--frontend", join(frontend, "dist"), "--foxglove-port", String(fox), "--foxglove-replay-port", String(replay),
    "--archives", join(tmp, "station2", "archives"), "--records", join(tmp, "station2", "records"),
    "--zenoh-connect", station.zenoh, "--zenoh-credentials", join(station.creds, "backend.cred"),
    "--deploy-key", join(station.creds, "deploy.key"),
  ], { cwd: repo, logFile: join(tmp, "station2-backend.log"), env: { MODD_ADMIN_PASSWORD: PASSWORD } });
  procs.push(backend);
  await waitForHttp(`${station.baseUrl}/openapi.json`, backend);
  return station;
}

/** Logs in as the admin (the journey's first step does it otherwise). */
function loginStep(page, baseUrl) {
  return ["log in", async () => {
    await page.goto(baseUrl);
    await page.getByLabel("User name").fill("admin");
    await page.getByLabel("Password").fill(PASSWORD);
    await page.getByRole("button", { name: "Log in" }).click();
    await page.getByRole("heading", { name: "MoDD projects" }).waitFor({ state: "visible", timeout: 10000 });
  }];
}

/**
 * The backend plans in worker processes started on the first request (each
 * imports the solver: seconds on a busy machine). One plan before the
 * journey, so that its steps are not timed against that start-up.
 */
async function warmPlanner(baseUrl) {
  const login = await fetch(`${baseUrl}/api/auth/login`, { method: "POST", headers: { "content-type": "application/json" },
    body: JSON.stringify({ username: "admin", password: PASSWORD }) });
  const { token } = await login.json();
  const model = scenario1(1, 2);
  const r = await fetch(`${baseUrl}/api/plan`, { method: "POST", headers: { "content-type": "application/json", authorization: `Bearer ${token}` },
    body: JSON.stringify({ model }), signal: AbortSignal.timeout(120000) });
  if (!r.ok) throw new Error(`warming the planner: HTTP ${r.status}`);
}

/** Scenario 1 as the journey builds it (no subscriber endpoints: zenoh delivery). */
function scenario1(pubPort, subPort) {
  const t = (v) => `usv.accelerometer.${v}`;
  const subs = [["accel_x", "2.0", "AVERAGE"], ["accel_y", "2.0", "AVERAGE"], ["accel_x", "0.25", "AVERAGE"],
    ["accel_y", "0.25", "AVERAGE"], ["accel_z", "0.25", "MIN"], ["accel_z", "0.25", "MAX"], ["accel_z", "0.25", "MAX"]];
  const model = {
    schemaVersion: "1.0",
    drone: { name: "usv", sensors: [{ name: "accelerometer", variables: ["accel_x", "accel_y", "accel_z"].map((name) => ({ name, unit: "METER_PER_SECOND_SQUARED" })) }] },
    pubBroker: { endpoint: { host: "127.0.0.1", port: pubPort }, logPath: "/tmp/modd/logs" },
    subBroker: { endpoint: { host: "127.0.0.1", port: subPort }, configPath: "/tmp/modd/conf" },
    publishers: [{ name: "pub_1", periodS: "0.04", topics: [t("accel_x"), t("accel_y"), t("accel_z")] }],
    subscribers: subs.map(([v, periodS, aggregation], i) => ({ name: `sub_${i + 1}`, topic: t(v), periodS, aggregation })),
  };
  // The survey's position and water sensors (views.mjs deploys a model that subscribes to them):
  // simulated from the start, so that they flow once that model is deployed.
  const survey = surveyParts();
  model.drone.sensors.push(...survey.sensors);
  model.publishers.push(survey.publisher);
  return model;
}

/** Scenario 1 plus the survey's sensors and subscriptions: the model views.mjs imports as a second project. */
function surveyModel(pubPort, subPort) {
  const m = scenario1(pubPort, subPort);
  m.subscribers.push(...surveyParts().subscribers);
  return m;
}

/** GPS and CTD sensors, their publisher (simulated: a lawnmower survey through a warm plume). */
export function surveyParts() {
  return {
    sensors: [
      { name: "gps", variables: [{ name: "latitude", unit: "NONE", type: "float64" }, { name: "longitude", unit: "NONE", type: "float64" }] },
      { name: "ctd", variables: [{ name: "water_temperature", unit: "DEGREE_CELSIUS" }] },
    ],
    publisher: { name: "pub_2", periodS: "0.2", topics: ["usv.gps.latitude", "usv.gps.longitude", "usv.ctd.water_temperature"] },
    subscribers: [
      { name: "sub_lat", topic: "usv.gps.latitude", periodS: "1.0", aggregation: "LAST" },
      { name: "sub_lon", topic: "usv.gps.longitude", periodS: "1.0", aggregation: "LAST" },
      { name: "sub_temp", topic: "usv.ctd.water_temperature", periodS: "1.0", aggregation: "AVERAGE" },
    ],
  };
}
