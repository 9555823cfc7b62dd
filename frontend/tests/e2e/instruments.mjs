/**
 * Plug-and-play instruments in the workbench (issue 32, "Done when"): the
 * integrator declares an NMEA GNSS, an NMEA echo sounder, an ASCII CTD and a
 * Modbus sonde in the form (kind, device, and per variable where its value
 * is), the designer has them published, the scientist subscribes, the model
 * is saved and deployed, and the operator's Monitor shows their values and
 * each instrument's health (state, last value, lines ok/bad, reconnects).
 *
 * The drone is `modd up --simulate` (run.mjs) started with the same four
 * instruments (`instrumentParts`): the simulator writes their wire formats
 * into pseudo-terminals (NMEA sentences, CSV lines, Modbus RTU replies) and
 * `modd-sensors` reads them, as on a drone; its health reaches the browser
 * through the PubBroker's STATUS and the SubBroker's status.
 */
import { expectCount, expectText, expectVisible, waitUntil } from "./journey.mjs";

/** The four instruments as the form declares them; `source` is each variable's mapping. */
const SENSORS = [
  { name: "gnss", kind: "nmea", path: "/dev/ttyGNSS", variables: [
    { name: "lat", unit: "deg", source: { "nmea.sentence": "GGA", "nmea.field": "lat" } },
    { name: "lon", unit: "deg", source: { "nmea.sentence": "GGA", "nmea.field": "lon" } }] },
  { name: "sounder", kind: "nmea", path: "/dev/ttySOUNDER", variables: [
    { name: "depth", unit: "METER", source: { "nmea.sentence": "DBT", "nmea.field": "depth_meters" } }] },
  { name: "sbe_ctd", kind: "ascii", path: "/dev/ttyCTD", variables: [
    { name: "temperature", unit: "DEGREE_CELSIUS", source: { "ascii.column": "1" } }] },
  { name: "sonde", kind: "modbus", path: "/dev/ttySONDE", variables: [
    { name: "ph", unit: "NONE", source: { "modbus.register": "0", "modbus.type": "float32" } },
    { name: "oxygen", unit: "mg/l", source: { "modbus.register": "2", "modbus.type": "uint16", "modbus.scale": "0.01" } }] },
];
const PERIOD_S = "0.5";

/** The same instruments in the model `modd up --simulate` runs (the drone's side). */
export function instrumentParts() {
  const mapping = (source) => {
    const out = {};
    for (const [path, value] of Object.entries(source)) {
      const [kind, key] = path.split(".");
      out[kind] ??= {};
      out[kind][key] = /^-?[\d.]+$/.test(value) ? Number(value) : value;
    }
    return out;
  };
  const sensors = SENSORS.map((s) => ({
    name: s.name, kind: s.kind, device: { path: s.path },
    variables: s.variables.map((v) => ({ name: v.name, unit: v.unit, ...mapping(v.source) })),
  }));
  const topics = SENSORS.flatMap((s) => s.variables.map((v) => `usv.${s.name}.${v.name}`));
  return { sensors, publisher: { name: "pub_instruments", periodS: PERIOD_S, topics } };
}

/** Added to the running drone (issue 39): on pseudo-terminals the journey makes (pty_instruments.py),
 * and one whose device is not there. */
const ADDED = (dir) => [
  { name: "gps2", kind: "nmea", path: `${dir}/gps2`, variables: [
    { name: "lat", unit: "deg", source: { "nmea.sentence": "GGA", "nmea.field": "lat" } }] },
  { name: "ctd2", kind: "ascii", path: `${dir}/ctd2`, variables: [
    { name: "temperature", unit: "DEGREE_CELSIUS", source: { "ascii.column": "1" } }] },
  { name: "echo2", kind: "nmea", path: `${dir}/not-plugged`, variables: [
    { name: "depth", unit: "METER", source: { "nmea.sentence": "DBT", "nmea.field": "depth_meters" } }] },
];

export function instruments({ page, ports, drone, liveValues, feedInstruments }) {
  const node = (id) => page.locator(`.react-flow__node[data-id="${id}"]`);
  const inspector = page.getByRole("region", { name: "Inspector" });
  const view = (name) => page.getByRole("tab", { name, exact: true }).click();
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  // A form field by its schema path: a list is chosen, a text typed and committed with Enter.
  const set = async (path, value) => {
    const f = inspector.locator(`[data-field="${path}"]`).locator("input, select").first();
    if (await f.evaluate((el) => el.tagName === "SELECT")) await f.selectOption(value);
    else {
      await f.fill(value);
      await f.press("Enter");
    }
  };
  const select = async (id) => {
    await node(id).click({ timeout: 5000 }).catch(() => node(id).dispatchEvent("click"));
    await expectVisible(inspector.locator("h2").first());
  };
  const topics = SENSORS.flatMap((s) => s.variables.map((v) => `usv.${s.name}.${v.name}`));
  const declare = async (sensors) => {
    await view("Sensor integrator");
    for (const s of sensors) {
      await page.getByRole("button", { name: "+ Sensor" }).click();
      await set("name", s.name);
      await set("kind", s.kind);
      await set("device.path", s.path);
      for (const [i, v] of s.variables.entries()) {
        if (i === 0) await select(`topic:${s.name}.var_1`);
        else await page.getByRole("button", { name: "+ Variable" }).click();
        await set("name", v.name);
        await set("unit", v.unit);
        for (const [path, value] of Object.entries(v.source)) await set(path, value);
      }
    }
  };
  const deployHead = async (revision) => {
    await view("Operator");
    await panel("Deploy");
    await page.getByRole("button", { name: `Deploy revision ${revision}` }).click();
    const result = page.getByTestId("deploy-result");
    await expectText(result, /Acked|failed/, 30000);
    if (!/Acked/.test((await result.textContent()) ?? "")) throw new Error(`deploy not acked: ${await result.textContent()}`);
    return Date.now();
  };
  const onboard = page.getByTestId("deploy-onboard");
  let dir = null;

  return [
    ["instruments: the integrator declares an NMEA GNSS, an NMEA sounder, an ASCII CTD and a Modbus sonde in the form", async () => {
      const projects = page.getByRole("heading", { name: "MoDD projects" });
      if (!(await projects.isVisible())) await page.getByRole("button", { name: "MoDD", exact: true }).click();
      await expectVisible(projects);
      await page.getByLabel("Project name").fill("instruments");
      await page.getByLabel("Drone name").fill("usv");
      await page.getByRole("button", { name: "Create" }).click();
      await expectVisible(node("drone"));
      await declare(SENSORS);
      await expectCount(page.locator(".react-flow__node.react-flow__node-topic"), topics.length);
    }],

    ["instruments: published, subscribed, saved and deployed", async () => {
      await view("System designer");
      await page.getByRole("button", { name: "+ Publisher" }).click();
      await set("periodS", PERIOD_S);
      for (const s of SENSORS) {
        if (s.variables.length > 1) await inspector.getByRole("button", { name: `All of ${s.name}` }).click();
        else await inspector.getByRole("checkbox", { name: new RegExp(`^usv\\.${s.name}\\.${s.variables[0].name} `) }).check();
      }
      await select("pubBroker");
      await set("endpoint.port", String(ports.pub));
      await select("subBroker");
      await set("endpoint.port", String(ports.sub));
      await view("Scientist");
      const quick = page.getByRole("form", { name: "Quick subscription" });
      for (const t of topics) {
        await quick.getByLabel("Topic").selectOption(t);
        await quick.getByLabel("Every (s)").fill("1.0");
        await quick.getByLabel("Aggregation").selectOption("LAST");
        await quick.getByRole("button", { name: "Subscribe" }).click();
      }
      await expectCount(page.locator(".react-flow__node .marker-error"), 0);
      await page.getByRole("button", { name: "Save", exact: true }).click();
      await expectText(page.locator(".topbar .revision"), /^r2$/);
      await view("Operator");
      await page.getByRole("button", { name: "Deploy revision 2" }).click();
      const result = page.getByTestId("deploy-result");
      await expectVisible(result, 30000);
      if (drone && !/Acked/.test((await result.textContent()) ?? "")) throw new Error(`deploy not acked: ${await result.textContent()}`);
    }],

    ["instruments: the operator sees their values and each one's health", async () => {
      if (!drone || !liveValues) throw new Error("needs the simulated drone (modd up --simulate)");
      await panel("Monitor");
      // one item of the link status line, opening on the table
      const summary = page.getByRole("status", { name: "Link status" }).locator("details.instruments-health summary");
      await expectText(summary, /Instruments: 4 \(4 open\)$/, 30000);
      await summary.click();
      const health = page.getByRole("table", { name: "Instruments' health" });
      await expectVisible(health);
      const rows = () => health.locator("tbody tr").evaluateAll((trs) => trs.map((tr) => [...tr.querySelectorAll("td")].map((td) => td.textContent)));
      // every instrument open, values received (a UTC time), lines counted and none refused
      await waitUntil(async () => {
        const r = await rows();
        return r.length === 4 && r.every(([, state, last, ok, bad]) => state === "open" && /UTC$/.test(last) && Number(ok) > 0 && bad === "0");
      }, 60000, async () => `instruments' health: ${JSON.stringify(await rows())}`);
      const names = (await rows()).map((r) => r[0]);
      if (names.join(",") !== "gnss,sbe_ctd,sonde,sounder") throw new Error(`instruments listed: ${names}`);
      // their values, charted from the deployed subscriptions
      for (const [i] of topics.entries()) {
        await page.getByRole("checkbox", { name: new RegExp(`^sub_${i + 1} `) }).check();
      }
      for (const [i] of topics.entries()) await expectText(page.getByTestId(`last-sub_${i + 1}`), /last -?\d/, 30000);
    }],

    // Issue 41: a drone's health field out of any range (2^63 ms, a negative count, a string)
    // leaves the Monitor working: the status the page receives is altered on its way in.
    ["instruments: a health field of 2^63 leaves the Monitor working", async () => {
      if (!drone || !liveValues) throw new Error("needs the simulated drone (modd up --simulate)");
      const hostile = { state: 1, lines_ok: 2 ** 63, lines_bad: -4, reconnects: "x", values: 1, last_value_ms: 2 ** 63 };
      let inject = true;
      await page.routeWebSocket(/\/stream(\?|$)/, (ws) => {
        const server = ws.connectToServer();
        ws.onMessage((m) => server.send(m));
        server.onMessage((m) => {
          try {
            const doc = JSON.parse(String(m));
            if (inject && doc.type === "status" && doc.data && doc.data.sensors) {
              doc.data.sensors.zz_hostile = hostile;
              ws.send(JSON.stringify(doc));
              return;
            }
          } catch { /* not JSON: passed on as it came */ }
          ws.send(m);
        });
      });
      await page.reload();
      await panel("Monitor");
      const summary = page.getByRole("status", { name: "Link status" }).locator("details.instruments-health summary");
      await expectText(summary, /Instruments: 5 /, 30000);
      await summary.click();
      const row = page.locator('tr[data-sensor="zz_hostile"]');
      await expectVisible(row);
      const cells = await row.locator("td").allTextContents();
      if (cells[2] !== "none yet" || cells[4] !== "0") throw new Error(`the hostile row reads ${JSON.stringify(cells)}`);
      if (await page.getByText(/panel failed/).count()) throw new Error("a panel failed on the hostile health");
      await expectText(page.getByRole("status", { name: "Link status" }), /link up/, 30000);  // live still shown
      inject = false;  // good data again: the hostile row leaves with it
      await page.reload();
      await panel("Monitor");
      await expectText(summary, /Instruments: 4 \(4 open\)$/, 30000);
    }],

    // Issue 39: a deploy reaches modd-sensors on the running drone (no restart): two instruments
    // added in the form read at once, a missing device said in the deploy result, a removed one stops.
    ["instruments: added on the running drone, read within 3 s of the deploy, no restart", async () => {
      if (!drone || !liveValues || !feedInstruments) throw new Error("needs the simulated drone (modd up --simulate)");
      dir = await feedInstruments();
      const added = ADDED(dir);
      await declare(added);
      await view("System designer");
      await page.getByRole("button", { name: "+ Publisher" }).click();
      await set("periodS", "0.2");
      for (const s of added) await inspector.getByRole("checkbox", { name: new RegExp(`^usv\\.${s.name}\\.${s.variables[0].name} `) }).check();
      await view("Scientist");
      const quick = page.getByRole("form", { name: "Quick subscription" });
      for (const t of ["usv.gps2.lat", "usv.ctd2.temperature"]) {
        await quick.getByLabel("Topic").selectOption(t);
        await quick.getByLabel("Every (s)").fill("0.5");
        await quick.getByLabel("Aggregation").selectOption("LAST");
        await quick.getByRole("button", { name: "Subscribe" }).click();
      }
      await expectCount(page.locator(".react-flow__node .marker-error"), 0);
      await page.getByRole("button", { name: "Save", exact: true }).click();
      await expectText(page.locator(".topbar .revision"), /^r3$/);
      const acked = await deployHead(3);
      // what each on-board process did: both new readers open, the missing device said
      await expectText(onboard, /gps2 started \(open\)/, 3000);
      await expectText(onboard, /ctd2 started \(open\)/, 100);
      await expectText(onboard.getByRole("alert"), new RegExp(`echo2 started — device ${dir}/not-plugged missing`), 100);
      await panel("Monitor");
      const line = page.getByTestId("onboard-sensors");
      await expectText(line, /gps2 started \(open\)/, Math.max(100, 3000 - (Date.now() - acked)));
      await expectText(line, /ctd2 started \(open\)/, 100);
      await expectText(line, /echo2 started — device .* missing/, 100);
      for (const sub of ["sub_7", "sub_8"]) await page.getByRole("checkbox", { name: new RegExp(`^${sub} `) }).check();
      for (const sub of ["sub_7", "sub_8"]) await expectText(page.getByTestId(`last-${sub}`), /last -?\d/, Math.max(100, 3000 - (Date.now() - acked)));
      const took = Date.now() - acked;
      console.log(`    new instruments' values in the Monitor ${took} ms after the ack`);
      // the instruments' health table follows the PubBroker's STATUS (at most one change STATUS per 10 s)
      const summary = page.getByRole("status", { name: "Link status" }).locator("details.instruments-health summary");
      await expectText(summary, /Instruments: 7 \(6 open, 1 closed\)/, 15000);
    }],

    ["instruments: removing one stops its reader", async () => {
      if (!dir) throw new Error("needs the instruments added above");
      // each view removes what it owns: the scientist the subscription, the designer the
      // publisher's topic, then the integrator the sensor
      const remove = async (id) => {
        await select(id);
        const button = page.getByRole("button", { name: "Delete", exact: true });
        if (await button.isDisabled()) throw new Error(`Delete is disabled: ${await button.getAttribute("title")}`);
        await button.click();
        await expectCount(node(id), 0);
      };
      await view("Scientist");
      await remove("sub:sub_8");
      await view("System designer");
      await select("pub:pub_2");
      await inspector.getByRole("checkbox", { name: /^usv\.ctd2\.temperature / }).uncheck();
      await view("Sensor integrator");
      await remove("sensor:ctd2");
      await expectCount(node("sensor:ctd2"), 0);
      await page.getByRole("button", { name: "Save", exact: true }).click();
      await expectText(page.locator(".topbar .revision"), /^r4$/);
      await deployHead(4);
      await expectText(onboard, /ctd2 stopped/, 3000);
      await expectText(onboard, /gps2 unchanged \(open\)/, 100);
      await panel("Monitor");
      const summary = page.getByRole("status", { name: "Link status" }).locator("details.instruments-health summary");
      await expectText(summary, /Instruments: 6 \(5 open, 1 closed\)/, 15000);
    }],
  ];
}
