/**
 * Issue 44's fleet journey (MODD_E2E_ONLY=fleet): a campaign of three drones
 * made from one mission model, each a real simulated drone (PubBroker,
 * SubBroker, simulator) on free loopback ports, the three brought up by one
 * `modd up --simulate` of the campaign, their SubBrokers joined to its one
 * station router, which the backend joins. In the browser: the campaign's .modd file imported as one project,
 * the Fleet panel shows the three drones on one map with their link, a
 * deploy to the three at once is acked by each, and one subscription to the
 * water temperature of every drone is accepted by each SubBroker in one step.
 */
import { mkdirSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { freePort, start } from "./processes.mjs";
import { expectText, expectVisible, waitUntil } from "./journey.mjs";

export const FLEET = ["usv1", "usv2", "usv3"];

/** The mission (scenario 1's accelerometer plus the survey's GPS and CTD, as run.mjs's surveyParts) and a Campaign of three vehicles, as .modd text. */
function campaignText(ports) {
  const vehicles = FLEET.map((n, i) => `    Vehicle ${n} "${n} boat" { channel = lake; PubBroker("127.0.0.1":${ports[i].pub}); SubBroker("127.0.0.1":${ports[i].sub}); }`);
  return [
    'Drone usv "Survey boat" {',
    "    Sensors {",
    "        Sensor accelerometer measures { accel_x(METER_PER_SECOND_SQUARED); accel_y(METER_PER_SECOND_SQUARED); accel_z(METER_PER_SECOND_SQUARED); }",
    "        Sensor gps measures { latitude(NONE, float64); longitude(NONE, float64); }",
    "        Sensor ctd measures { water_temperature(DEGREE_CELSIUS); }",
    "    }",
    "}",
    `PubBroker("127.0.0.1":${ports[0].pub}, "/tmp/modd/logs");`,
    `SubBroker("127.0.0.1":${ports[0].sub}, "/tmp/modd/conf");`,
    "Publishers {",
    '    Publisher pub_1(0.04, "usv.accelerometer.accel_x", "usv.accelerometer.accel_y", "usv.accelerometer.accel_z");',
    '    Publisher pub_2(0.2, "usv.gps.latitude", "usv.gps.longitude", "usv.ctd.water_temperature");',
    "}",
    "Subscriptions {",
    '    Subscriber sub_1("usv.accelerometer.accel_x", 2.0, AVERAGE);',
    '    Subscriber sub_lat("usv.gps.latitude", 1.0, LAST);',
    '    Subscriber sub_lon("usv.gps.longitude", 1.0, LAST);',
    '    Subscriber sub_temp("usv.ctd.water_temperature", 1.0, AVERAGE);',
    "}",
    'Campaign lake "Three boats on one lake" {',
    "    Channel lake { rate = 100000; }",
    ...vehicles,
    "}",
    "",
  ].join("\n");
}

/**
 * Starts the three drones in one command: `modd up lake.modd --simulate` brings up every
 * vehicle of the campaign (each its PubBroker, simulator and SubBroker) and one station router
 * their SubBrokers join; returns the campaign's text and the zenoh endpoint the backend
 * connects to. `procs` gets the `modd up` process (stopped by PID with the others: it stops
 * every process of the campaign).
 */
export async function startFleet({ repo, bin, tmp, creds, pubbrokerBin, procs }) {
  const ports = [];
  for (const _ of FLEET) ports.push({ pub: await freePort(), sub: await freePort() });
  const text = campaignText(ports);
  const dir = join(tmp, "fleet");
  mkdirSync(dir, { recursive: true });
  writeFileSync(join(dir, "lake.modd"), text);
  const zenoh = `tcp/127.0.0.1:${await freePort()}`;
  procs.push(start("modd up lake", [join(bin, "modd"), "up", join(dir, "lake.modd"), "--workdir", join(dir, "run"),
    "--credentials", creds, "--zenoh-listen", zenoh, "--simulate"],
  { cwd: repo, logFile: join(dir, "up.log"), env: { MODD_PUBBROKER: pubbrokerBin } }));
  return { text, endpoints: [zenoh] };
}

export function fleetJourney({ page, imagesDir, fleet }) {
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  const view = (name) => page.getByRole("tab", { name, exact: true }).click();
  const row = (n) => page.getByTestId(`fleet-row-${n}`);
  return [
    ["fleet: a campaign of three drones imported from one mission model, each with its link up", async () => {
      await page.locator('input[type="file"]').setInputFiles({ name: "lake.modd", mimeType: "text/plain", buffer: Buffer.from(fleet.text) });
      await page.locator('.react-flow__node[data-id="drone"]').waitFor({ state: "visible", timeout: 20000 });
      await panel("Fleet");
      await expectText(page.locator(".fleet-panel"), /Campaign lake: 3 drones; channel lake: usv1, usv2, usv3/, 20000);
      for (const n of FLEET) await expectText(row(n).getByTestId("fleet-link"), /^up$/, 90000);
    }],
    ["fleet: deployed to the three at once, each acked by its own drone", async () => {
      await view("Operator");
      await panel("Fleet");
      await page.getByRole("button", { name: "Deploy revision 1 to 3 drones" }).click();
      for (const n of FLEET) await expectText(page.getByTestId(`fleet-ack-${n}`), new RegExp(`^${n}: revision 1 acked$`), 60000);
      for (const n of FLEET) await expectText(row(n).getByTestId("fleet-deployed"), /^r1 acked$/, 10000);
    }],
    ["fleet: every drone on one map, at its last fix", async () => {
      const canvas = page.getByTestId("fleet-canvas");
      await waitUntil(async () => (await canvas.getAttribute("data-drones")) === "3", 60000,
        async () => `drones placed: ${await canvas.getAttribute("data-drones")}; ${await page.getByTestId("fleet-fixes").textContent()}`);
      const placed = JSON.parse((await canvas.getAttribute("data-placed")) ?? "[]");
      if (placed.map((p) => p[0]).join() !== FLEET.join()) throw new Error(`placed: ${JSON.stringify(placed)}`);
      await expectVisible(page.getByText(/3 of 3 drones placed at their last fix \(sub_lat, sub_lon\)/));
      await page.screenshot({ path: join(imagesDir, "fleet.png") });
    }],
    ["fleet: the water temperature of every drone subscribed in one step", async () => {
      await view("Scientist");
      await panel("Fleet");
      const form = page.getByRole("region", { name: "Subscribe on every drone" });
      await form.getByLabel("Variable", { exact: true }).selectOption("ctd.water_temperature");
      await form.getByLabel("Period (s)", { exact: true }).fill("2");
      await form.getByLabel("Subscription name", { exact: true }).fill("temp_all");
      await form.getByRole("button", { name: "Subscribe on every drone" }).click();
      for (const n of FLEET) {
        await expectText(page.getByTestId(`fleet-sub-${n}`),
          new RegExp(`^${n}: ${n}\\.ctd\\.water_temperature ACCEPTED on modd/${n}/sub/temp_all$`), 30000);
      }
      console.log(`    fleet: ${FLEET.join(", ")} acked one deploy and accepted one subscription each`);
    }],
  ];
}
