/**
 * Issue 45, "Alerts": the scientist adds a threshold alert on a variable of
 * the demo in the text view (accel_x, the simulated deck swinging ±0.8 m/s² at
 * 0.3 Hz, crosses 0.5 upwards every 3.3 s: no value is injected); the operator
 * deploys it; the banner shows in the scientist's view, and the time from the
 * window's delivery by the SubBroker (its `delivered_ns`, same host clock) to the
 * banner in the page is measured and printed (at most 1 s); the Monitor's chart
 * marks it; the operator's Monitor lists it among the active alerts, and the
 * signal's crossing back clears it.
 *
 * MODD_E2E_ONLY=alerts runs these steps alone (after logging in).
 */
import { join } from "node:path";
import { expectText, expectVisible, importProject, waitUntil } from "./journey.mjs";

const LEVEL = 0.5;
const HYSTERESIS = 0.1;
const ALERT_LINE = `    Subscriber high_x("usv.accelerometer.accel_x", 0.5, THRESHOLD(UP ${LEVEL}, ${HYSTERESIS}), alert = scientist + operator);\n`;

export function alertsJourney({ page, model, liveValues, imagesDir }) {
  const view = (name) => page.getByRole("tab", { name, exact: true }).click();
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  const banner = page.getByTestId("alert-banner");
  return [
    ["alerts: the scientist adds a threshold alert in the text view (inspector shows its roles)", async () => {
      if (!liveValues) throw new Error("no simulated drone: no signal to cross a level");
      await importProject(page, "deck-alert.json", model);
      await view("Scientist");
      await panel("Text");
      await expectText(page.locator(".cm-content"), /Subscriber sub_7/);
      // Before the closing brace of Subscriptions, the text's last line.
      await page.locator(".cm-content").click();
      await page.keyboard.press("Control+End");
      const last = await page.locator(".cm-line").last().textContent();
      if (!last?.trim()) await page.keyboard.press("ArrowUp");
      await page.keyboard.press("Home");
      await page.keyboard.insertText(ALERT_LINE);
      await page.getByRole("button", { name: "Apply text to diagram" }).click();
      await expectText(page.locator(".text-toolbar [role=status]"), /unsaved edits|Applied/);
      const node = page.locator('.react-flow__node[data-id="sub:high_x"]');
      await node.click();
      const roles = page.getByRole("region", { name: "Inspector" }).locator('[data-field="alert"]');
      await expectVisible(roles);
      for (const [role, on] of [["scientist", true], ["operator", true], ["designer", false]]) {
        if ((await roles.getByLabel(role).isChecked()) !== on) throw new Error(`alert role ${role}: expected ${on ? "ticked" : "not ticked"}`);
      }
      await page.getByRole("button", { name: "Save", exact: true }).click();
      await expectText(page.locator(".topbar .revision"), /^r\d+$/);
    }],

    ["alerts: the operator deploys it; the banner shows within 1 s of the window's arrival", async () => {
      await view("Operator");
      await page.getByRole("button", { name: /^Deploy revision \d+$/ }).click();
      await expectText(page.getByTestId("deploy-result"), /Acked/, 30000);
      await view("Scientist");
      // Every banner the page shows, when it showed (the page's clock), with its window's delivery.
      await page.evaluate(() => {
        const seen = (window.__alertsSeen = []);
        const note = () => {
          const b = document.querySelector('[data-testid="alert-banner"]');
          const id = b?.getAttribute("data-alert");
          if (b && id && !seen.some((s) => s.id === id)) {
            seen.push({ id, seenMs: Date.now(), eventNs: Number(b.getAttribute("data-event-ns")), deliveredNs: Number(b.getAttribute("data-delivered-ns")) });
          }
        };
        new MutationObserver(note).observe(document.body, { subtree: true, childList: true, attributes: true, attributeFilter: ["data-alert"] });
        note();
      });
      await expectVisible(banner, 30000);
      if ((await banner.getAttribute("role")) !== "alert") throw new Error("the banner is not role=alert");
      await expectText(banner, /high_x: usv\.accelerometer\.accel_x above 0\.5/);
      if (await page.getByLabel("Alert sound").first().isChecked()) throw new Error("the alert sound is on by default");
      await page.screenshot({ path: join(imagesDir, "alert-banner.png") });
      // A few alerts (acknowledged one by one, so each next crossing shows anew).
      for (let i = 0; i < 3; i += 1) {
        await waitUntil(async () => (await page.evaluate(() => window.__alertsSeen.length)) > i, 15000, async () => "no new alert banner");
        await banner.getByRole("button", { name: /^Acknowledge/ }).last().click();
      }
      const seen = await page.evaluate(() => window.__alertsSeen);
      const lat = seen.map((s) => s.seenMs - s.deliveredNs / 1e6);
      const sinceSample = seen.map((s) => s.seenMs - s.eventNs / 1e6);
      console.log(`    alert banner: ${seen.length} alerts, ms from the window's delivery (SubBroker delivered_ns) to the banner: `
        + `${lat.map((x) => x.toFixed(0)).join(", ")} (max ${Math.max(...lat).toFixed(0)}); from the crossing sample: ${sinceSample.map((x) => x.toFixed(0)).join(", ")}`);
      for (const [i, s] of seen.entries()) {
        if (!(s.deliveredNs > 0) || lat[i] > 1000 || lat[i] < -50) throw new Error(`banner ${s.id}: ${lat[i]} ms after its window's delivery`);
        // The true time: the crossing sample's, inside the 0.5 s window delivered after it (not the arrival).
        if (!(s.eventNs < s.deliveredNs && s.deliveredNs - s.eventNs < 3e9)) throw new Error(`banner ${s.id}: event ${s.eventNs} vs delivered ${s.deliveredNs}`);
      }
    }],

    ["alerts: the Monitor's chart marks it at the crossing sample's time", async () => {
      await panel("Monitor");
      await page.getByRole("checkbox", { name: /high_x/ }).check();
      await expectVisible(page.getByTestId("chart-high_x"));
      await expectText(page.getByTestId("chart-high_x").getByTestId("chart-alerts"), /\d+ alerts? marked, last at \d/, 15000);
    }],

    ["alerts: the operator's Monitor lists it while active; the crossing back clears it", async () => {
      await view("Operator");
      await panel("Monitor");
      const list = page.getByRole("region", { name: "Active alerts" });
      await expectVisible(list);
      const item = list.getByTestId("active-alert-high_x");
      await expectVisible(item, 15000);
      await expectText(item, /accel_x above 0\.5 \(0\.\d+ at /);
      await page.screenshot({ path: join(imagesDir, "monitor-active-alerts.png") });
      const value = Number((await item.textContent()).match(/\((-?[\d.]+) at /)[1]);
      if (!(value > LEVEL + HYSTERESIS)) throw new Error(`the alert's sample ${value} is not above level + hysteresis`);
      // The signal swings back below 0.4 within a period (3.3 s): the alert is no longer active.
      await item.waitFor({ state: "detached", timeout: 10000 });
      // ...and the next crossing raises the next one.
      await expectVisible(item, 10000);
      await item.getByRole("button", { name: "Clear" }).click();
      await item.waitFor({ state: "detached", timeout: 2000 });
    }],
  ];
}
