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
import { mkdirSync } from "node:fs";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { expectText, expectVisible } from "./journey.mjs";

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

export function metadataJourney({ page, imagesDir, model, liveValues }) {
  mkdirSync(imagesDir, { recursive: true });
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  const form = page.getByRole("form", { name: "Dataset metadata" });
  return [
    ["dataset metadata: filled, a located fault, saved with the project", async () => {
      if (!liveValues) throw new Error("no simulated drone: no archive to export");
      await page.getByRole("button", { name: "MoDD", exact: true }).click().catch(() => undefined);
      await page.getByRole("heading", { name: "MoDD projects" }).waitFor({ state: "visible", timeout: 10000 });
      await page.locator('input[type="file"]').setInputFiles({ name: "bay-survey.json", mimeType: "application/json", buffer: Buffer.from(JSON.stringify(model)) });
      await page.locator('.react-flow__node[data-id="drone"]').waitFor({ state: "visible", timeout: 20000 });
      await panel("Archives");
      const files = page.getByRole("table", { name: "Archive files" });
      await expectText(files, /\.mcap/, 20000);
      await files.locator("button.link").first().click();
      await page.locator(".dataset-metadata summary").click();
      await expectText(form.getByLabel("Asked for by data centres"), /creator_name/);
      for (const [label, value] of Object.entries(FILLED)) await form.getByLabel(label, { exact: true }).fill(value);
      await form.getByLabel("Naming authority", { exact: true }).fill("modd");
      await form.getByRole("button", { name: "Save metadata" }).click();
      await expectText(form.locator("#dm-naming_authority-error"), /not reversed DNS/);
      await page.screenshot({ path: join(imagesDir, "dataset-metadata-error.png") });
      await form.getByLabel("Naming authority", { exact: true }).fill("org.example.marine");
      await form.getByRole("button", { name: "Save metadata" }).click();
      await expectText(form.getByRole("status"), /Saved revision 1/);
      await page.screenshot({ path: join(imagesDir, "dataset-metadata.png") });
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
      await page.screenshot({ path: join(imagesDir, "export-notes.png") });
    }],
  ];
}
