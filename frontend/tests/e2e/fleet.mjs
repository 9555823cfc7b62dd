/**
 * Issue 44's fleet journey (MODD_E2E_ONLY=fleet): a campaign of three drones
 * made from one mission model, each a real simulated drone (PubBroker,
 * SubBroker, simulator) on free loopback ports, the three brought up by one
 * `modd up --simulate` of the campaign, their SubBrokers joined to its one
 * station router, which the backend joins. In the browser: the mission's .modd
 * file (one drone) imported as one project, made the campaign of the three with
 * the Inspector's campaign form (as the campaign's text for `modd up` was) and saved;
 * the Fleet panel shows the three drones on one map with their link, a
 * deploy to the three at once is acked by each, and one subscription to the
 * water temperature of every drone is accepted by each SubBroker in one step.
 */
import { mkdirSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { freePort, start } from "./processes.mjs";
import { expectText, expectVisible, waitUntil } from "./journey.mjs";

export const FLEET = ["usv1", "usv2", "usv3"];

/** The mission (scenario 1's accelerometer plus the survey's GPS and CTD, as run.mjs's surveyParts), one drone, as .modd text. */
function missionText(ports) {
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
    "",
  ].join("\n");
}

/** The mission and a Campaign of three vehicles, as .modd text (the drones' models are expanded from it). */
function campaignText(ports) {
  const vehicles = FLEET.map((n, i) => `    Vehicle ${n} "${n} boat" { channel = lake; PubBroker("127.0.0.1":${ports[i].pub}); SubBroker("127.0.0.1":${ports[i].sub}); }`);
  return [
    missionText(ports).trimEnd(),
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
  return { text, mission: missionText(ports), ports, endpoints: [zenoh] };
}

/**
 * The campaign of the text (campaignText) made by a person in the Inspector's campaign form of
 * the one-drone mission: two vehicles and a third, named after the fleet, each on channel lake,
 * the second and third on their own brokers (the first keeps the mission's, which are its own).
 */
async function makeCampaign(page, ports, imagesDir) {
  const form = page.getByRole("region", { name: "Inspector" }).getByRole("region", { name: "Campaign" });
  const commit = async (input, text) => { await input.fill(text); await input.press("Enter"); };
  await form.getByRole("button", { name: "Make it a campaign" }).click();
  await form.getByRole("button", { name: "Add vehicle" }).click();
  await commit(form.locator('form > .field[data-field="name"] input'), "lake");
  await commit(form.locator('form > .field[data-field="description"] input'), "Three boats on one lake");
  await form.getByRole("button", { name: "Add channel" }).click();
  await commit(form.getByRole("group", { name: "Channel ch_1" }).getByLabel(/^rate bps/), "100000");
  await commit(form.getByRole("group", { name: "Channel ch_1" }).getByLabel(/^name/), "lake");
  for (const [i, name] of FLEET.entries()) {
    let vehicle = form.getByRole("group", { name: `Vehicle usv_${i + 1}` });
    await commit(vehicle.getByLabel(/^name/), name);
    vehicle = form.getByRole("group", { name: `Vehicle ${name}` });
    await commit(vehicle.getByLabel(/^description/), `${name} boat`);
    await vehicle.getByLabel(/^channel/).selectOption("lake");
    if (i === 0) continue;
    await commit(vehicle.getByLabel(/^pub broker endpoint port/), String(ports[i].pub));
    await vehicle.getByText("SubBroker: the mission's").click();
    await commit(vehicle.getByLabel(/^sub broker endpoint host/), "127.0.0.1");
    await commit(vehicle.getByLabel(/^sub broker endpoint port/), String(ports[i].sub));
  }
  await expectText(form.getByRole("group", { name: "Channel lake" }), /Vehicles on it: usv1, usv2, usv3/, 5000);
  await page.screenshot({ path: join(imagesDir, "fleet-campaign-form.png") });
}

export function fleetJourney({ page, imagesDir, fleet }) {
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  const view = (name) => page.getByRole("tab", { name, exact: true }).click();
  const row = (n) => page.getByTestId(`fleet-row-${n}`);
  return [
    ["fleet: a campaign of three drones made from one mission model with the Inspector's campaign form, saved, each with its link up", async () => {
      await page.locator('input[type="file"]').setInputFiles({ name: "lake.modd", mimeType: "text/plain", buffer: Buffer.from(fleet.mission) });
      await page.locator('.react-flow__node[data-id="drone"]').waitFor({ state: "visible", timeout: 20000 });
      await view("System designer");
      await makeCampaign(page, fleet.ports, imagesDir);
      await page.getByRole("button", { name: "Save", exact: true }).click();
      await expectText(page.locator(".topbar .revision"), /^r2$/, 20000);
      await panel("Fleet");
      await expectText(page.locator(".fleet-panel"), /Campaign lake: 3 drones; channel lake: usv1, usv2, usv3/, 20000);
      for (const n of FLEET) await expectText(row(n).getByTestId("fleet-link"), /^up$/, 90000);
    }],
    ["fleet: deployed to the three at once, each acked by its own drone", async () => {
      await view("Operator");
      await panel("Fleet");
      await page.getByRole("button", { name: "Deploy revision 2 to 3 drones" }).click();
      for (const n of FLEET) await expectText(page.getByTestId(`fleet-ack-${n}`), new RegExp(`^${n}: revision 2 acked$`), 60000);
      for (const n of FLEET) await expectText(row(n).getByTestId("fleet-deployed"), /^r2 acked$/, 10000);
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
