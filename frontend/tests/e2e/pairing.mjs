/**
 * Pairing a freshly installed drone (issue 43): the operator makes the pairing
 * bundle in the Deploy panel (a `usv.modd-pair` download and a one-time code shown
 * once); the test imports it with `modd-pair` into an empty configuration folder
 * (the drone's /etc/modd), starts the PubBroker from those files alone and the base
 * station's SubBroker with the link key the workbench kept for that drone; the
 * operator's deploy is acknowledged by that drone. A copy with one byte flipped and
 * the right code is refused, and writes nothing.
 *
 * The base station is a second one (run.mjs's pairingStation: its own backend, zenoh
 * endpoint and credentials; this SubBroker serves that endpoint), so that these steps
 * run in the full `npm run test:e2e` beside `modd up`'s drone usv, and alone with
 * MODD_E2E_ONLY=pairing.
 */
import { execFileSync } from "node:child_process";
import { existsSync, mkdirSync, readFileSync, statSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { expectText, expectVisible, waitUntil } from "./journey.mjs";
import { start } from "./processes.mjs";

/** `modd-pair FILE --config-dir DIR`, the code on standard input: { code, out }. */
function moddPair(bin, file, dir, code) {
  try {
    const out = execFileSync(join(bin, "modd-pair"), [file, "--config-dir", dir, "--code-file", "-"],
      { input: `${code}\n`, encoding: "utf8", stdio: ["pipe", "pipe", "pipe"] });
    return { code: 0, out };
  } catch (e) {
    return { code: e.status, out: `${e.stdout}${e.stderr}` };
  }
}

export function pairing({ page, imagesDir, bin, tmp, model, pubbrokerBin, station, procs }) {
  const view = (name) => page.getByRole("tab", { name, exact: true }).click();
  const made = page.getByTestId("pairing-made");
  const paired = { code: "", file: "" };
  return [
    ["pairing: the operator makes the bundle of drone usv; its code is shown once", async () => {
      await page.getByRole("button", { name: "MoDD", exact: true }).click().catch(() => undefined);
      await page.getByRole("heading", { name: "MoDD projects" }).waitFor({ state: "visible", timeout: 10000 });
      await page.locator('input[type="file"]').setInputFiles({ name: "paired-usv.json", mimeType: "application/json", buffer: Buffer.from(JSON.stringify(model)) });
      await page.locator('.react-flow__node[data-id="drone"]').waitFor({ state: "visible", timeout: 20000 });
      await view("Operator");
      const section = page.getByRole("region", { name: "Pair a drone" });
      await section.scrollIntoViewIfNeeded();
      const [download] = await Promise.all([
        page.waitForEvent("download", { timeout: 30000 }),
        section.getByRole("button", { name: /Make the pairing bundle/ }).click(),
      ]);
      if (download.suggestedFilename() !== "usv.modd-pair") throw new Error(`bundle named ${download.suggestedFilename()}`);
      paired.file = join(tmp, "usv.modd-pair");
      await download.saveAs(paired.file);
      await expectVisible(made);
      paired.code = (await made.getByLabel("Pairing code").textContent()) ?? "";
      if (!/^[0-9A-Z]{5}(-[0-9A-Z]{5}){3}$/.test(paired.code)) throw new Error(`pairing code shown: "${paired.code}"`);
      const bundle = readFileSync(paired.file, "utf8");
      if (bundle.includes(paired.code) || bundle.includes(paired.code.replaceAll("-", ""))) throw new Error("the code is inside the bundle");
      await expectText(made, new RegExp(join(station.dataDir, "pairing", "link-keys", "usv.key").replaceAll(".", "\\.")));
      await made.scrollIntoViewIfNeeded();
      await page.waitForTimeout(200);
      await page.screenshot({ path: join(imagesDir, "pairing.png") });
    }],

    ["pairing: a tampered copy is refused; the bundle imported into a fresh drone", async () => {
      const bad = readFileSync(paired.file);
      bad[Math.floor(bad.length / 3)] ^= 0x04;
      writeFileSync(join(tmp, "tampered.modd-pair"), bad);
      const refused = moddPair(bin, join(tmp, "tampered.modd-pair"), join(tmp, "tampered-etc"), paired.code);
      if (refused.code !== 1 || !/refused: the bundle (was altered|is damaged)/.test(refused.out)) throw new Error(`tampered copy: ${JSON.stringify(refused)}`);
      if (existsSync(join(tmp, "tampered-etc"))) throw new Error("a refused bundle wrote files");
      const etc = join(tmp, "fresh-drone", "etc", "modd");
      const ok = moddPair(bin, paired.file, etc, paired.code);
      if (ok.code !== 0 || !/drone 'usv' paired with base station SHA256:/.test(ok.out)) throw new Error(`modd-pair: ${JSON.stringify(ok)}`);
      const mode = statSync(join(etc, "link.key")).mode & 0o777;
      if (mode !== 0o600) throw new Error(`link.key mode ${mode.toString(8)}`);
      const fingerprint = (await made.getByLabel("Station fingerprint").textContent()) ?? "";
      if (!ok.out.includes(fingerprint)) throw new Error(`modd-pair pinned another station than ${fingerprint}: ${ok.out}`);
    }],

    ["pairing: the paired drone acknowledges the operator's deploy", async () => {
      const etc = join(tmp, "fresh-drone", "etc", "modd");
      mkdirSync(model.pubBroker.logPath, { recursive: true });
      const wrongKey = { MODD_LINK_KEY: "not-the-paired-key" }; // each side reads its key file
      procs.push(start("paired pubbroker", [pubbrokerBin, "--config", join(etc, "pubbroker.json")],
        { logFile: join(tmp, "paired-pubbroker.log"), env: wrongKey }));
      const stationModel = join(tmp, "station-usv.json");
      writeFileSync(stationModel, JSON.stringify(model));
      const keyFile = join(station.dataDir, "pairing", "link-keys", "usv.key");
      procs.push(start("paired subbroker", [join(bin, "modd-subbroker"), "--model", stationModel, "--key", `file:${keyFile}`,
        "--zenoh-listen", station.zenoh, "--credentials", station.creds, "--no-tcp-delivery"],
      { logFile: join(tmp, "paired-subbroker.log"), env: wrongKey }));
      const sbLog = () => (existsSync(join(tmp, "paired-subbroker.log")) ? readFileSync(join(tmp, "paired-subbroker.log"), "utf8") : "");
      // linked: the SubBroker authenticated with the paired PubBroker and its config runs
      await waitUntil(async () => /config \d+ running/.test(sbLog()), 60000,
        async () => `the paired drone never linked up:\n${sbLog().split("\n").slice(-8).join("\n")}`);
      // the workbench's zenoh session opens once this station's router is up (it retries every
      // 0.5 s): a deploy before then fails with "not reachable", and is asked again
      const deployed = page.getByTestId("deploy-result");
      let text = "";
      for (let i = 0; i < 20 && !/Acked/.test(text); i += 1) {
        if (i) await page.waitForTimeout(1000);
        await page.getByRole("button", { name: /^Deploy revision \d+$/ }).click();
        await expectVisible(deployed, 30000);
        text = (await deployed.textContent()) ?? "";
        if (!/Acked|not reachable/.test(text)) break;
      }
      if (!/Acked by the drone \(usv/.test(text)) throw new Error(`deploy: ${text}\n${sbLog().split("\n").slice(-8).join("\n")}`);
      await expectText(page.getByRole("region", { name: "Deployment history" }), /acked/);
    }],
  ];
}
