/**
 * Declared resolution and the radio's budget (issue 34), as a scientist clicks
 * them: scenario 1 imported with a LoRa SF7 radio at a 1 % duty cycle and
 * 0.01 m/s² on the accelerometer; the Plan panel shows the air time, the share
 * of the duty cycle, the energy and the nearest plans that fit (figures from the
 * planner, on the backend). The integrator drops accel_z's resolution (full
 * precision: more bytes), the scientist asks 0.05 on its two subscriptions
 * (fewer): every figure follows. Before the edits, the scientist calibrates the
 * plan by a test flight's archive the backend holds (a smooth signal near 0:
 * smaller deltas than the declared ranges assume), then goes back to the
 * declared ranges; the figures are the backend planner's for the same model,
 * asked by the test itself.
 */
import { execFileSync } from "node:child_process";
import { mkdirSync, rmSync } from "node:fs";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { waitUntil } from "./journey.mjs";

const here = dirname(fileURLToPath(import.meta.url));
const python = resolve(here, "../../../.venv/bin/python");
const FLIGHT = "test_flight.mcap";

const MODEL = `
Drone usv {
    Sensors {
        Sensor accelerometer measures {
            accel_x(METER_PER_SECOND_SQUARED) { validMin = -20; validMax = 20; resolution = 0.01; };
            accel_y(METER_PER_SECOND_SQUARED) { validMin = -20; validMax = 20; resolution = 0.01; };
            accel_z(METER_PER_SECOND_SQUARED) { validMin = -20; validMax = 20; resolution = 0.01; };
        }
    }
}
PubBroker("127.0.0.1":7171, "/tmp/modd/logs");
SubBroker("127.0.0.1":7272, "/tmp/modd/conf");
Link { transport = serial; device = "/dev/ttyUSB0"; radio = lora; sf = 7; bandwidth = 125000; dutyCycle = 0.01; }
Publishers {
    Publisher pub_1("127.0.0.1":7373, 0.04, "usv.accelerometer.accel_x", "usv.accelerometer.accel_y", "usv.accelerometer.accel_z");
}
Subscriptions {
    Subscriber sub_1("usv.accelerometer.accel_x", 2.0, AVERAGE);
    Subscriber sub_2("usv.accelerometer.accel_y", 2.0, AVERAGE);
    Subscriber sub_3("usv.accelerometer.accel_x", 0.25, AVERAGE);
    Subscriber sub_4("usv.accelerometer.accel_y", 0.25, AVERAGE);
    Subscriber sub_5("usv.accelerometer.accel_z", 0.25, MIN);
    Subscriber sub_6("usv.accelerometer.accel_z", 0.25, MAX);
}
`;

// A figure's number past its hedge ("about 266.2 s", "at most 32.4 s": the planner's label).
const seconds = (t) => Number.parseFloat(t.replace(/^[^\d-]*/, ""));

/** The backend planner's `radio` for MODEL (the .modd text, parsed by the backend), calibrated by `calibrate` if given. */
async function plannedRadio(baseUrl, password, calibrate) {
  const login = await fetch(`${baseUrl}/api/auth/login`, { method: "POST", headers: { "content-type": "application/json" },
    body: JSON.stringify({ username: "admin", password }) });
  const { token } = await login.json();
  const query = calibrate ? `?calibrate=${encodeURIComponent(calibrate)}` : "";
  const r = await fetch(`${baseUrl}/api/plan${query}`, { method: "POST", headers: { "content-type": "application/json", authorization: `Bearer ${token}` },
    body: JSON.stringify({ text: MODEL }), signal: AbortSignal.timeout(60000) });
  const out = await r.json();
  if (!r.ok || !out.plan?.radio) throw new Error(`planning ${calibrate ?? "uncalibrated"}: HTTP ${r.status} ${JSON.stringify(out).slice(0, 300)}`);
  return out.plan.radio;
}

export function radio({ page, baseUrl, password, archiveDir }) {
  const node = (id) => page.locator(`.react-flow__node[data-id="${id}"]`);
  const inspector = page.getByRole("region", { name: "Inspector" });
  const field = (path) => inspector.locator(`[data-field="${path}"]`).locator("input, select").first();
  const view = (name) => page.getByRole("tab", { name, exact: true }).click();
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  const select = async (id) => {
    await node(id).click();
    await inspector.locator("h2").first().waitFor({ state: "visible", timeout: 10000 });
  };
  const figures = async () => Object.fromEntries(await Promise.all(["air-time", "duty-share", "energy"].map(
    async (id) => [id, (await page.getByTestId(id).textContent()) ?? ""])));
  const proposals = async () => (await page.getByTestId("proposal").allTextContents()).join(" | ");
  const changed = async (before, what) => {
    await waitUntil(async () => {
      const now = await figures();
      return Object.keys(before).every((k) => now[k] !== before[k]);
    }, 20000, async () => `${what}: figures stayed ${JSON.stringify(await figures())}`);
  };

  return [
    ["radio budget: a LoRa plan with declared resolutions, refused with the proposals that fit", async () => {
      await page.getByRole("button", { name: "MoDD", exact: true }).click().catch(() => undefined);
      await page.locator('input[type="file"]').setInputFiles({ name: "lora.modd", mimeType: "text/plain", buffer: Buffer.from(MODEL) });
      await node("drone").waitFor({ state: "visible", timeout: 20000 });
      await panel("Plan");
      await page.getByTestId("air-time").waitFor({ state: "visible", timeout: 30000 });
      await waitUntil(async () => /LoRa|lora/i.test((await page.getByTestId("radio-kind").textContent()) ?? ""), 10000);
      await page.getByTestId("radio-error").waitFor({ state: "visible", timeout: 10000 });
      await waitUntil(async () => (await page.getByTestId("proposal").count()) > 0, 10000, proposals);
    }],

    ["radio budget: calibrated by a test flight's archive, smaller 'about' figures; the declared ranges bring them back", async () => {
      // The test flight lands in the backend's archive directory while the workbench is open.
      mkdirSync(archiveDir, { recursive: true });
      const flight = join(archiveDir, FLIGHT);
      execFileSync("nice", [python, join(here, "flight_archive.py"), flight, "60"], { stdio: "inherit" });
      try {
        const [declared, calibrated] = await Promise.all([plannedRadio(baseUrl, password, null), plannedRadio(baseUrl, password, `usv/${FLIGHT}`)]);
        const shown = (r) => ({ "air-time": `about ${r.air_time_s_per_hour.toFixed(1)} s`, energy: `about ${r.energy_j_per_hour.toFixed(1)} J` });
        if (declared.figures !== "estimate" || calibrated.figures !== "estimate" || calibrated.calibrated_from !== FLIGHT)
          throw new Error(`the planner's figures: ${declared.figures}, ${calibrated.figures} from ${calibrated.calibrated_from}`);
        if (!(calibrated.air_time_s_per_hour < declared.air_time_s_per_hour))
          throw new Error(`calibrated air time ${calibrated.air_time_s_per_hour} s/h, not below ${declared.air_time_s_per_hour}`);
        const showing = async (want) => {
          const now = await figures();
          return Object.entries(want).every(([k, v]) => now[k] === v);
        };
        const expectShown = (want, what) => waitUntil(() => showing(want), 20000,
          async () => `${what}: the panel shows ${JSON.stringify(await figures())}, the planner ${JSON.stringify(want)}`);
        await expectShown(shown(declared), "declared ranges");
        const picker = page.getByRole("combobox", { name: "Calibrate by archive" });
        await picker.waitFor({ state: "visible", timeout: 10000 });
        await picker.focus();
        await waitUntil(async () => (await picker.locator("option").allTextContents()).includes(FLIGHT), 10000,
          async () => `${FLIGHT} not among the picker's ${JSON.stringify(await picker.locator("option").allTextContents())}`);
        await picker.selectOption({ label: FLIGHT });
        const from = page.getByTestId("calibrated-from");
        await waitUntil(async () => (await from.textContent().catch(() => ""))?.startsWith(
          `Quantised values sized from ${FLIGHT} (${calibrated.calibration.streams.length} streams`), 20000,
          async () => `calibrated-from says "${await from.textContent().catch(() => "(nothing)")}"`);
        await expectShown(shown(calibrated), `calibrated by ${FLIGHT}`);
        await picker.selectOption({ label: "no archive (declared ranges)" });
        await expectShown(shown(declared), "back to the declared ranges");
        await from.waitFor({ state: "detached", timeout: 10000 });
      } finally {
        rmSync(flight, { force: true }); // the drone's archive directory as it was
      }
    }],

    ["radio budget: full precision on accel_z costs air time, energy and changes the proposals", async () => {
      const before = await figures();
      const offers = await proposals();
      await view("Sensor integrator"); // a variable's resolution is the integrator's to edit
      await select("topic:accelerometer.accel_z");
      const f = field("resolution");
      await f.fill("");
      await f.press("Enter");
      await panel("Plan");
      await changed(before, "accel_z without a resolution");
      const after = await figures();
      if (!(seconds(after["air-time"]) > seconds(before["air-time"])))
        throw new Error(`air time ${before["air-time"]} -> ${after["air-time"]}: expected more`);
      await waitUntil(async () => (await proposals()) !== offers, 10000, async () => `proposals stayed ${offers}`);
    }],

    ["radio budget: the scientist asks 0.05 m/s² on the subscriptions of accel_z: less air time", async () => {
      const before = await figures();
      await view("Scientist");
      for (const sub of ["sub_5", "sub_6"]) {
        await select(`sub:${sub}`);
        await field("resolution").fill("0.05");
        await field("resolution").press("Enter");
      }
      await panel("Plan");
      await changed(before, "sub_5 and sub_6 at 0.05");
      const after = await figures();
      if (!(seconds(after["air-time"]) < seconds(before["air-time"])))
        throw new Error(`air time ${before["air-time"]} -> ${after["air-time"]}: expected less`);
    }],
  ];
}
