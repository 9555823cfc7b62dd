/**
 * Issue 40's journey: the scientist fills the dataset metadata (Archives →
 * Dataset metadata), a located fault first (a naming authority that is not
 * reversed DNS), saves it with the project, exports the archive as NetCDF
 * and the file carries it — read back with netCDF4 (the Unidata library, not
 * MoDD's writer); the export's notes are shown and the download is named by
 * the backend (drone and time span).
 *
 * MODD_E2E_ONLY=metadata runs it alone (after logging in). Needs the simulated
 * drone's archive (`modd up --simulate`).
 */
import { execFileSync } from "node:child_process";
import { mkdirSync, writeFileSync } from "node:fs";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { expectText, expectVisible, importProject, waitUntil } from "./journey.mjs";

const here = dirname(fileURLToPath(import.meta.url));
const python = resolve(here, "../../../.venv/bin/python");
//: The global attributes and the instrument variable of a NetCDF file, as netCDF4 reads them.
const READ = "import json, sys, netCDF4\n"
  + "with netCDF4.Dataset(sys.argv[1]) as ds:\n"
  + "    inst = ds.variables.get('instrument_accelerometer')\n"
  + "    print(json.dumps({'attrs': {k: str(ds.getncattr(k)) for k in ds.ncattrs()},\n"
  + "        'instrument': {k: str(inst.getncattr(k)) for k in inst.ncattrs()} if inst is not None else None}))\n";

const FILLED = {
  Title: "Bay survey with the demo drone",
  Summary: "Accelerations measured by a surface drone (simulated).",
  Keywords: "ocean, motion",
  "Creator name": "Ana Example",
  "Creator e-mail": "ana@marine.example.org",
  "Publisher name": "Example Data Centre",
  Institution: "Example Marine Institute",
  License: "CC-BY-4.0",
  Project: "Test bay survey",
  "Platform id": "usv01",
  "Platform vocabulary": "https://mmisw.org/ont/ioos/platform",
  "Instrument accelerometer make": "Bosch",
  "Instrument accelerometer model": "BMI088",
  "Instrument accelerometer serial number": "4711",
};

//: QARTOD tests of the accelerometer's x axis: on its 2 s AVERAGE windows live (sub_1), on its samples in the file.
const QC = {
  "usv.accelerometer.accel_x": {
    spike_test: { suspect_threshold: 2, fail_threshold: 5 },
    flat_line_test: { suspect_threshold: 6, fail_threshold: 12, tolerance: 0.001 },
  },
};

/** The backend's API as the admin (a Bearer token), for what the journey sets up off-screen. */
async function adminApi(baseUrl, password) {
  const r = await fetch(`${baseUrl}/api/auth/login`, { method: "POST", headers: { "content-type": "application/json" },
    body: JSON.stringify({ username: "admin", password }) });
  const { token } = await r.json();
  return async (method, path, body) => {
    const res = await fetch(`${baseUrl}${path}`, { method, headers: { "content-type": "application/json", authorization: `Bearer ${token}` },
      body: body === undefined ? undefined : JSON.stringify(body), signal: AbortSignal.timeout(60000) });
    const text = await res.text();
    if (!res.ok) throw new Error(`${method} ${path}: HTTP ${res.status} ${text.slice(0, 300)}`);
    return res.headers.get("content-type")?.includes("json") ? JSON.parse(text) : text;
  };
}

export function metadataJourney({ page, imagesDir, model, liveValues, baseUrl, password, faultsFile }) {
  mkdirSync(imagesDir, { recursive: true });
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  const form = page.getByRole("form", { name: "Dataset metadata" });
  // The panel over the whole window, for its photographs.
  const expand = async (on) => {
    const b = page.locator(".dock-toggle");
    if ((await b.getAttribute("aria-pressed")) !== String(on)) await b.click();
  };
  const photo = async (locator, name) => {
    await locator.scrollIntoViewIfNeeded();
    await page.waitForTimeout(300);
    await page.screenshot({ path: join(imagesDir, `${name}.png`) });
  };
  return [
    ["dataset metadata: filled, a located fault, saved with the project", async () => {
      if (!liveValues) throw new Error("no simulated drone: no archive to export");
      await importProject(page, "bay-survey.json", model);
      await panel("Archives");
      await expand(true);
      const files = page.getByRole("table", { name: "Archive files" });
      await expectText(files, /\.mcap/, 20000);
      await files.locator("button.link").first().click();
      await page.locator(".dataset-metadata summary").click();
      await expectText(form.getByLabel("Asked for by data centres"), /creator_name/);
      for (const [label, value] of Object.entries(FILLED)) await form.getByLabel(label, { exact: true }).fill(value);
      await form.getByLabel("Naming authority", { exact: true }).fill("modd");
      await form.getByRole("button", { name: "Save metadata" }).click();
      await expectText(form.locator("#dm-naming_authority-error"), /not reversed DNS/);
      await photo(form.getByLabel("Naming authority", { exact: true }), "dataset-metadata-error");
      await form.getByLabel("Naming authority", { exact: true }).fill("org.example.marine");
      await form.getByRole("button", { name: "Save metadata" }).click();
      await expectText(form.getByRole("status"), /Saved revision 1/);
      await photo(form.getByLabel("Title", { exact: true }), "dataset-metadata");
    }],

    ["dataset metadata: the NetCDF export carries it (read with netCDF4), named by the backend, notes shown", async () => {
      const exportForm = page.getByRole("form", { name: "Export dataset" });
      await exportForm.getByLabel("Dataset format").selectOption("netcdf");
      const [download] = await Promise.all([
        page.waitForEvent("download", { timeout: 60000 }),
        exportForm.getByRole("button", { name: "Export", exact: true }).click(),
      ]);
      const name = download.suggestedFilename();
      if (!/^usv-dataset-\d{8}T\d{6}Z-\d{8}T\d{6}Z\.nc$/.test(name)) throw new Error(`download named ${name}`);
      const got = JSON.parse(execFileSync(python, ["-c", READ, await download.path()], { encoding: "utf8" }));
      const want = {
        title: FILLED.Title, creator_name: "Ana Example", creator_email: "ana@marine.example.org",
        naming_authority: "org.example.marine", license: "CC-BY-4.0", keywords: "ocean, motion",
        institution: "Example Marine Institute", project: "Test bay survey", publisher_name: "Example Data Centre",
      };
      for (const [k, v] of Object.entries(want)) {
        if (got.attrs[k] !== v) throw new Error(`global attribute ${k}: ${JSON.stringify(got.attrs[k])}, not ${JSON.stringify(v)}`);
      }
      if (got.instrument?.make_model !== "Bosch BMI088" || got.instrument?.serial_number !== "4711") {
        throw new Error(`instrument_accelerometer: ${JSON.stringify(got.instrument)}`);
      }
      await expectText(exportForm.getByRole("status"), new RegExp(`Saved ${name.replace(/\./g, "\\.")}`));
      // The export's notes: what ACDD/IOOS still ask for that the form left empty (publisher_email).
      const notes = exportForm.getByRole("list", { name: "Export notes" });
      await expectVisible(notes);
      await expectText(notes, /ask for [^;]*publisher_email/);
      await photo(notes, "export-notes");
    }],

    ["quality flags: a spike and a stuck value injected into the simulated accelerometer, marked in the Monitor and flagged in the file", async () => {
      const api = await adminApi(baseUrl, password);
      const project = (await api("GET", "/api/projects")).find((p) => p.name === "bay-survey");
      if (!project) throw new Error("no project bay-survey");
      // The QARTOD tests (the form keeps a saved qc section), then the project deployed: the backend
      // flags the live windows of what runs on the drone with its project's tests.
      const meta = await api("GET", `/api/projects/${project.id}/dataset-metadata`);
      await api("PUT", `/api/projects/${project.id}/dataset-metadata`, { base_revision: meta.revision, metadata: { ...meta.metadata, qc: QC } });
      const deployed = await api("POST", `/api/projects/${project.id}/deployments`, { revision: null });
      if (deployed.status !== "acked") throw new Error(`deploy: ${JSON.stringify(deployed).slice(0, 300)}`);
      await panel("Monitor");
      await expand(true);
      const box = page.getByRole("checkbox", { name: /sub_1 / });
      if (!(await box.isChecked())) await box.check();
      await expectText(page.getByTestId("last-sub_1"), /last -?\d/, 60000);
      const chart = page.locator("figure.live-chart", { has: page.getByTestId("last-sub_1") });
      const caption = chart.getByTestId("chart-gaps");
      const bad = async () => Number(/(\d+) bad\)/.exec((await caption.textContent()) ?? "")?.[1] ?? 0);
      const before = await bad();
      const now = Date.now() / 1000;
      const inject = (fault) => writeFileSync(faultsFile, JSON.stringify({ faults: [{ topic: "usv.accelerometer.accel_x", ...fault }] }));
      // A spike: one sample +500 m/s² (its 2 s window's mean +10), in 3 s.
      inject({ kind: "spike", at: now + 3, offset: 500 });
      await waitUntil(async () => (await bad()) > before, 30000, async () => `after the spike, the caption says "${await caption.textContent()}"`);
      await page.waitForTimeout(8000); // the windows around it flagged for good (a flag revises the window before only)
      const spiked = await bad();
      await photo(chart, "monitor-qc-spike");
      // Then the axis stuck for 20 s: FAIL once 12 s of its windows are flat (flat_line_test, above).
      const flatFrom = Date.now() / 1000 + 1;
      inject({ kind: "flat", from: flatFrom, to: flatFrom + 20 });
      await waitUntil(async () => (await bad()) > spiked, 60000, async () => `after the flat line, the caption says "${await caption.textContent()}"`);
      if (Date.now() / 1000 - flatFrom < 10) throw new Error(`flagged ${(Date.now() / 1000 - flatFrom).toFixed(1)} s into the flat line: not by the flat line test`);
      await photo(chart, "monitor-qc");
      await expand(false);
      await page.waitForTimeout(Math.max(0, (flatFrom + 21 - Date.now() / 1000) * 1000)); // the flat line over
      // The file: the spike's sample flagged FAIL (4) in the CSV's qc_agg column (the export's ioos_qc run).
      const csv = await api("POST", "/api/drones/usv/archives/export", { model, format: "csv", topics: ["usv.accelerometer.accel_x"],
        project: project.id, start_ns: Math.round((now - 5) * 1e9) });
      const rows = csv.trim().split("\n");
      const head = rows[0].split(",").map((h) => h.replace(/"/g, ""));
      const [value, qc] = [head.indexOf("value"), head.indexOf("qc_agg")];
      if (qc < 0) throw new Error(`no qc_agg column: ${rows[0]}`);
      const flagged = rows.slice(1).map((r) => r.split(",")).filter((c) => Number(c[value]) > 100);
      if (flagged.length !== 1 || flagged[0][qc] !== "4") throw new Error(`the spike in the file: ${JSON.stringify(flagged)}`);
      // And the stuck value: its 25 Hz samples flagged FAIL once 12 s flat (the timed tests run in scaled time).
      const at = head.indexOf("time");
      const stuck = rows.slice(1).map((r) => r.split(",")).filter((c) => {
        const t = Date.parse(c[at].replace(/"/g, "")) / 1000;
        return t > flatFrom + 13 && t < flatFrom + 19;
      });
      if (stuck.length < 50 || stuck.some((c) => c[qc] !== "4")) throw new Error(`the stuck value in the file: ${stuck.length} samples, flags ${[...new Set(stuck.map((c) => c[qc]))]}`);
    }],
  ];
}
