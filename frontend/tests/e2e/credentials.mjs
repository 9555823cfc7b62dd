/**
 * Issue 42: a credential file deleted by hand is made anew with a new secret
 * at the next start, and said where it matters. The viewer credential file of
 * the running test instance (the one the scientists' stubs name) is deleted,
 * the base station restarted as after a reboot (its SubBroker stopped by PID;
 * `modd up` starts it again); the SubBroker's log says which file was made
 * anew, and the Downloads panel announces it (GET /api/credentials/remade),
 * photographed for the operator's guide.
 *
 * MODD_E2E_ONLY=credentials runs it alone (after logging in). Needs the drone
 * (`modd up`); it runs last in the whole journey (it restarts the SubBroker).
 */
import { existsSync, readFileSync, unlinkSync } from "node:fs";
import { join } from "node:path";
import { expectText, expectVisible, waitUntil } from "./journey.mjs";
import { childPids } from "./views.mjs";

export function credentialsJourney({ page, imagesDir, model, credsDir, droneDir, dronePid }) {
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  const expand = async (on) => {
    const b = page.locator(".dock-toggle");
    if ((await b.getAttribute("aria-pressed")) !== String(on)) await b.click();
  };
  return [
    ["a deleted viewer credential file: made anew at the base station's restart, said in its log and in the Downloads panel", async () => {
      if (!dronePid) throw new Error("needs the drone (make build)");
      const viewer = join(credsDir, "viewer.cred");
      const log = join(droneDir, "logs", "subbroker.log");
      const said = /zenoh credentials missing from .* were made anew with new secrets: viewer\.cred; copies handed out before no longer work/;
      const before = readFileSync(viewer, "utf8");
      // A project's Downloads panel: nothing to announce yet.
      await page.getByRole("button", { name: "MoDD", exact: true }).click().catch(() => undefined);
      await page.getByRole("heading", { name: "MoDD projects" }).waitFor({ state: "visible", timeout: 10000 });
      await page.locator('input[type="file"]').setInputFiles({ name: "field-team.json", mimeType: "application/json", buffer: Buffer.from(JSON.stringify(model)) });
      await page.locator('.react-flow__node[data-id="drone"]').waitFor({ state: "visible", timeout: 20000 });
      await panel("Downloads");
      await expectVisible(page.getByRole("button", { name: /^Download / }).first());
      if (await page.getByTestId("credentials-remade").count()) throw new Error("a credential announced as made anew before any was deleted");
      if (said.test(readFileSync(log, "utf8"))) throw new Error("the SubBroker's log says viewer.cred was made anew before it was deleted");
      // Deleted by hand; the base station restarts (its SubBroker stopped; modd up starts it again).
      unlinkSync(viewer);
      const [subbroker] = childPids(dronePid, "modd-subbroker");
      if (!subbroker) throw new Error(`no modd-subbroker under modd up (pid ${dronePid})`);
      process.kill(subbroker, "SIGTERM");
      await waitUntil(async () => existsSync(viewer) && childPids(dronePid, "modd-subbroker").some((p) => p !== subbroker), 60000,
        async () => `viewer.cred ${existsSync(viewer) ? "is back" : "is not made again"}; SubBrokers under modd up: ${childPids(dronePid, "modd-subbroker").join(", ") || "none"}`);
      if (readFileSync(viewer, "utf8") === before) throw new Error("viewer.cred made again with the same secret");
      // The log says it...
      await waitUntil(async () => said.test(readFileSync(log, "utf8")), 20000, async () => `not in ${log}: ${said}`);
      // ...and the Downloads panel, where the stubs that name the file are downloaded.
      await page.reload();
      await page.locator('.react-flow__node[data-id="drone"]').waitFor({ state: "visible", timeout: 20000 });
      await panel("Downloads");
      const notice = page.getByTestId("credentials-remade");
      await expectText(notice, /viewer\.cred \(the scientists' viewer credential \(their subscriber stubs name it\)\) was missing and was made anew with a new secret at \d{4}-\d\d-\d\d \d\d:\d\d:\d\dZ/, 20000);
      await expectText(notice, /Copies handed out before no longer work: download again and hand out the new ones/);
      await expand(true);
      await page.waitForTimeout(300);
      await page.screenshot({ path: join(imagesDir, "downloads-credentials-remade.png") });
      await expand(false);
      // The restarted SubBroker serves the link again.
      await panel("Monitor");
      await expectText(page.getByRole("status", { name: "Link status" }), /link up/, 60000);
      console.log(`    credentials: viewer.cred deleted, made anew at the SubBroker's restart (pid ${subbroker} → ${childPids(dronePid, "modd-subbroker").join(", ")}), said in subbroker.log and the Downloads panel`);
    }],
  ];
}
