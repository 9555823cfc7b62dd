/**
 * The workbench journey, as a person would click it (docs/user-guide/):
 * log in, create an empty project, build scenario 1 of the paper in the four
 * role views, see the live plan's buffer sizes 28, 28, 6, exercise undo/redo,
 * copy/paste, delete, the text view, save, deploy and watch live values.
 * Every view is photographed into docs/images/ for the user guide.
 *
 * `steps` runs the named steps in order; after a failure the rest are
 * reported as not run.
 */
import { mkdirSync, readFileSync } from "node:fs";
import { join } from "node:path";

export function journey({ page, baseUrl, password, imagesDir, ports, drone, liveValues }) {
  mkdirSync(imagesDir, { recursive: true });
  // Photographs once the live plan has caught up with the last edit.
  const shot = async (name) => {
    const rev = page.locator(".topbar .revision");
    if (await rev.count()) await waitUntil(async () => !/planning/.test((await rev.textContent()) ?? ""), 10000).catch(() => undefined);
    await page.waitForTimeout(150);
    await page.screenshot({ path: join(imagesDir, `${name}.png`) });
  };
  const node = (id) => page.locator(`.react-flow__node[data-id="${id}"]`);
  const inspector = page.getByRole("region", { name: "Inspector" });
  const field = (path) => inspector.locator(`[data-field="${path}"]`).locator("input, select").first();
  const setText = async (path, value) => {
    const f = field(path);
    await f.fill(value);
    await f.press("Enter");
  };
  const setSelect = async (path, value) => field(path).selectOption(value);
  const view = (name) => page.getByRole("tab", { name, exact: true }).click();
  const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
  const expand = async (on) => {
    const b = page.locator(".dock-toggle");
    if ((await b.getAttribute("aria-pressed")) !== String(on)) await b.click();
  };
  const select = async (id) => {
    await node(id).click();
    await expectVisible(inspector.locator("h2").first());
  };
  const layout = async () => {
    await page.getByRole("button", { name: "Auto-layout" }).click();
    await page.waitForTimeout(600);
  };
  const connect = async (source, target) => {
    const a = await node(source).locator(".react-flow__handle.source").boundingBox();
    const b = await node(target).locator(".react-flow__handle.target").boundingBox();
    if (!a || !b) throw new Error(`handles of ${source} → ${target} are not visible`);
    await page.mouse.move(a.x + a.width / 2, a.y + a.height / 2);
    await page.mouse.down();
    await page.mouse.move((a.x + b.x) / 2, (a.y + b.y) / 2, { steps: 5 });
    await page.mouse.move(b.x + b.width / 2, b.y + b.height / 2, { steps: 5 });
    await page.mouse.up();
  };
  const clickPane = () => page.locator(".react-flow__pane").click({ position: { x: 8, y: 8 } });

  return [
    ["log in", async () => {
      await page.goto(baseUrl);
      await page.getByLabel("User name").fill("admin");
      await page.getByLabel("Password").fill("wrong-password");
      await page.getByRole("button", { name: "Log in" }).click();
      await expectText(page.getByRole("alert"), /wrong user name or password/);
      await page.getByLabel("Password").fill(password);
      await shot("login");
      await page.getByRole("button", { name: "Log in" }).click();
      await expectVisible(page.getByRole("heading", { name: "MoDD projects" }));
    }],

    ["import a model of the original tool (.collector, windows-1252)", async () => {
      const original = [
        "// Mission de température – essai à 25 °C (saved by Eclipse in windows-1252)",
        "DataCollector {",
        "    Drone 'boat' { Sensors { Sensor \"imu\" measures { ax(METER_PER_SECOND_SQUARED); } } }",
        "    PubBroker broker(localhost:7171, '/logs');",
        "    SubBroker base(\"127.0.0.1\":7272, \"/conf\");",
        "    Publishers { Publisher imu(\"127.0.0.1\":7171, 4.0E-2, \"boat.imu.ax\") }",
        "    Subscriptions {",
        "        Subscriber a(\"127.0.0.1\":7401, \"boat.imu.ax\", 2.0, AVERAGE)",
        "        Subscriber b(\"127.0.0.1\":7401, \"boat.imu.ax\", .25, MAX)",
        "    }",
        "}",
      ].join("\n");
      // windows-1252 bytes: é=0xe9, –=0x96, à=0xe0, °=0xb0
      const cp1252 = (text) => Buffer.from([...text].map((c) => ({ "–": 0x96 })[c] ?? c.charCodeAt(0)));
      const input = page.locator('input[type="file"]');
      // a syntax error: listed under the import with its line
      await input.setInputFiles({ name: "original.collector", mimeType: "text/plain", buffer: cp1252(original.replace(".25, MAX)", ".25 MAX)")) });
      await expectText(page.getByRole("list", { name: "Import problems" }), /line 9:\d+: error: unexpected 'MAX'/);
      await expectText(page.getByRole("status").filter({ hasText: "windows-1252" }), /not UTF-8/);
      // the file as the original tool wrote it: opens; the shared endpoint is a warning on its node
      await input.setInputFiles({ name: "original.collector", mimeType: "text/plain", buffer: cp1252(original) });
      await expectVisible(node("drone"));
      await expectVisible(node("sub:b").locator(".marker-warning"));
      await page.getByRole("button", { name: "MoDD", exact: true }).click();
      await expectVisible(page.getByRole("heading", { name: "MoDD projects" }));
    }],

    ["create an empty project", async () => {
      await page.getByLabel("Project name").fill("scenario1");
      await page.getByLabel("Drone name").fill("usv");
      await shot("projects");
      await page.getByRole("button", { name: "Create" }).click();
      await expectVisible(node("drone"));
      await expectCount(page.locator(".react-flow__node"), 3);
    }],

    ["integrator: sensor and measured variables", async () => {
      await view("Sensor integrator");
      await expectDisabled(page.getByRole("button", { name: "+ Publisher" }));
      await page.getByRole("button", { name: "+ Sensor" }).click();
      await setText("name", "accelerometer");
      await expectVisible(node("sensor:accelerometer"));
      await select("topic:accelerometer.var_1"); // named like the variables + Variable adds
      await setText("name", "accel_x");
      await setText("unit", "METER_PER_SECOND_SQUARED");
      for (const v of ["accel_y", "accel_z"]) {
        await page.getByRole("button", { name: "+ Variable" }).click();
        await setText("name", v);
        await setText("unit", "METER_PER_SECOND_SQUARED");
      }
      await expectCount(page.locator(".react-flow__node.react-flow__node-topic"), 3);
      await layout();
      await select("topic:accelerometer.accel_z");
      // A generic sensor's variable: no MAVLink field mapping in the inspector.
      if (await page.locator('.inspector [data-field^="source"]').count()) throw new Error("MAVLink fields shown for a generic sensor's variable");
      await shot("integrator");
    }],

    ["designer: publisher connected by dragging", async () => {
      await view("System designer");
      await expectDisabled(page.getByRole("button", { name: "+ Sensor" }));
      await page.getByRole("button", { name: "+ Publisher" }).click();
      await setText("periodS", "0.04");
      await layout();
      for (const v of ["accel_x", "accel_y", "accel_z"]) await connect("pub:pub_1", `topic:accelerometer.${v}`);
      await expectCount(page.locator(".react-flow__edge.edge-publishes"), 3);
      // The brokers on free loopback ports (the simulated drone runs this model).
      await select("pubBroker");
      await setText("endpoint.port", String(ports.pub));
      await select("subBroker");
      await setText("endpoint.port", String(ports.sub));
      await expectText(node("subBroker"), new RegExp(`127\\.0\\.0\\.1:${ports.sub}`));
      await select("pub:pub_1");
      await expectText(node("pub:pub_1"), /every 0\.04 s/);
      await shot("designer");
    }],

    ["scientist: seven subscriptions", async () => {
      await view("Scientist");
      await expectDisabled(page.getByRole("button", { name: "+ Sensor" }));
      const quick = page.getByRole("form", { name: "Quick subscription" });
      // Readable: the topics grouped by sensor, each by its full name with its unit.
      const groups = await quick.getByLabel("Topic").locator("optgroup").evaluateAll((gs) => gs.map((g) => g.label));
      if (!groups.some((g) => g.startsWith("accelerometer"))) throw new Error(`quick subscription topics not grouped by sensor: ${JSON.stringify(groups)}`);
      // Each topic under its sensor by its variable and unit (the full name its tooltip), none cut by the narrow palette.
      await expectText(quick.getByLabel("Topic").locator("option").first(), /^accel_x \(m\/s²\)$/);
      if (await quick.getByLabel("Topic").locator("option").first().getAttribute("title") !== "usv.accelerometer.accel_x (m/s²)") throw new Error("the topic's full name is not its tooltip");
      const cut = await quick.getByLabel("Topic").evaluate((select) => {
        const ctx = document.createElement("canvas").getContext("2d");
        const room = select.clientWidth - 2 * parseFloat(getComputedStyle(select).paddingLeft) - 8; // an option's own padding
        return [...select.options].filter((o) => { ctx.font = getComputedStyle(o).font; return ctx.measureText(o.textContent).width > room; }).map((o) => o.textContent);
      });
      if (cut.length) throw new Error(`topics cut by the palette's width: ${cut.join(", ")}`);
      const subs = [
        ["accel_x", "2.0", "AVERAGE"], ["accel_y", "2.0", "AVERAGE"], ["accel_x", "0.25", "AVERAGE"],
        ["accel_y", "0.25", "AVERAGE"], ["accel_z", "0.25", "MIN"], ["accel_z", "0.25", "MAX"],
      ];
      for (const [v, period, agg] of subs) {
        await quick.getByLabel("Topic").selectOption(`usv.accelerometer.${v}`);
        await quick.getByLabel("Every (s)").fill(period);
        await quick.getByLabel("Aggregation").selectOption(agg);
        await quick.getByRole("button", { name: "Subscribe" }).click();
      }
      // The seventh by hand: a bare subscriber is flagged until it has a topic.
      await page.getByRole("button", { name: "+ Subscriber" }).click();
      await layout();
      await expectVisible(node("sub:sub_7").locator(".marker-error"));
      await expectText(inspector, /topic: required/);
      await shot("validation");
      await connect("topic:accelerometer.accel_z", "sub:sub_7");
      await select("sub:sub_7");
      await setText("periodS", "0.25");
      await setSelect("aggregation", "MAX");
      await expectText(node("sub:sub_7"), /MAX every 0\.25 s/);
      await expectCount(page.locator(".react-flow__node .marker-error"), 0);
    }],

    ["live plan: buffer sizes 28, 28, 6", async () => {
      await panel("Plan");
      await waitUntil(async () => (await page.getByTestId("buffer-size").allTextContents()).join(",") === "28,28,6", 20000,
        async () => `buffer sizes ${(await page.getByTestId("buffer-size").allTextContents()).join(",")}`);
      await expectText(page.getByTestId("hyperperiod"), /2\.0 s/);
      await expectText(node("topic:accelerometer.accel_z"), /n = 6/);
      await clickPane();
      await shot("scientist");
      await page.getByRole("button", { name: "Zoom in", exact: true }).click();
      await expand(true);
      await shot("plan");
      await expand(false);
    }],

    ["topic names shown consistently: diagram, plan, inspector, monitor (full name and unit, as quick subscription)", async () => {
      const x = "usv.accelerometer.accel_x (m/s²)";
      const literal = (t) => new RegExp(t.replace(/[.*+?^${}()|[\]\\]/g, "\\$&"));
      // Diagram: the measured variable's node and a subscriber's node.
      await expectText(node("topic:accelerometer.accel_x").locator(".node-detail"), literal(x));
      await expectText(node("sub:sub_1").locator(".node-detail"), literal(`${x} AVERAGE every 2.0 s`));
      // Plan: the buffer table's topic column.
      await panel("Plan");
      await expectText(page.getByRole("table", { name: "Buffer sizes" }).locator("tbody tr").first().locator("td").first(), literal(x));
      // Inspector: the subscriber's topic field.
      await select("sub:sub_1");
      const chosen = await field("topic").evaluate((el) => el.selectedOptions[0]?.textContent ?? "");
      if (chosen !== x) throw new Error(`inspector topic shows "${chosen}", not "${x}"`);
      // Monitor: the watch list and the dynamic subscription's topics.
      await panel("Monitor");
      await expectText(page.getByRole("complementary", { name: "Subscriptions to watch" }).locator("label").first(), literal(`sub_1 ${x} AVERAGE every 2.0 s`));
      const dyn = await page.getByRole("form", { name: "Dynamic subscription" }).getByLabel("Topic").locator("option").first().textContent();
      if (dyn !== x) throw new Error(`dynamic subscription offers "${dyn}", not "${x}"`);
      await panel("Plan");
      await clickPane();
    }],

    ["undo, redo, copy, paste, delete", async () => {
      await clickPane();
      await page.keyboard.press("Control+z");
      await expectText(node("sub:sub_7"), /AVERAGE every 0\.25 s/);
      await page.keyboard.press("Control+Shift+z");
      await expectText(node("sub:sub_7"), /MAX every 0\.25 s/);
      await node("sub:sub_7").click();
      await page.keyboard.press("Control+c");
      await page.keyboard.press("Control+v");
      await expectVisible(node("sub:sub_7_copy"));
      await page.keyboard.press("Delete");
      await expectCount(node("sub:sub_7_copy"), 0);
      await expectCount(page.locator(".react-flow__node.react-flow__node-subscriber"), 7);
    }],

    ["designer: the link and a publisher's edge selected on the diagram; the radio set by form, the plan's air time follows", async () => {
      await view("System designer");
      await clickPane();
      // The mouse on the link edge (a straight line: clicked at its middle, where a person would).
      const box = await page.locator(".react-flow__edge.edge-link path.react-flow__edge-interaction").boundingBox();
      if (!box) throw new Error("the link edge is not on screen");
      await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
      await expectVisible(inspector.getByRole("heading", { name: /^Link/ }));
      await setSelect("radio.kind", "sik");
      await panel("Plan");
      await waitUntil(async () => /sik/i.test((await page.getByTestId("radio-kind").textContent().catch(() => "")) ?? ""), 10000, async () => "no SiK radio in the plan");
      const seconds = async () => Number(/([\d.]+) s/.exec((await page.getByTestId("air-time").textContent()) ?? "")?.[1]);
      const fast = await seconds();
      await setText("radio.airRateBps", "16000"); // a quarter of the SiK default: four times the air time
      await waitUntil(async () => (await seconds()) > fast * 3, 10000, async () => `air time ${await seconds()} s after a 4x slower radio (was ${fast} s)`);
      await shot("designer-link");
      // The keyboard on a publisher → topic edge: Tab reaches it, Enter selects it.
      await page.locator(".react-flow__edge.edge-publishes").first().focus();
      await page.keyboard.press("Enter");
      await expectVisible(inspector.getByRole("heading", { name: "Publisher → topic" }));
      await expectVisible(inspector.getByRole("button", { name: "Delete this edge" }));
      // Both radio edits undone: the model is scenario 1 again for the steps after this one.
      await clickPane();
      await page.keyboard.press("Control+z");
      await page.keyboard.press("Control+z");
      await expectCount(page.getByTestId("radio-kind"), 0);
      await view("Scientist"); // where the steps after this one start
    }],

    ["save", async () => {
      await page.getByRole("button", { name: "Save", exact: true }).click();
      await expectText(page.locator(".topbar .revision"), /^r2$/);
    }],

    ["text view: saved text, unsaved diagram edits, a syntax error at line:col", async () => {
      await panel("Text");
      await expectText(page.locator(".cm-content"), /Subscriber sub_7/);
      await shot("text");
      // The text follows a diagram edit before any save, and its undo.
      await select("sub:sub_7");
      await setText("periodS", "0.5");
      await expectText(page.locator(".cm-content"), /sub_7\([^)]*0\.5, MAX\)/);
      await expectText(page.locator(".text-toolbar [role=status]"), /unsaved edits/);
      await clickPane();
      await page.keyboard.press("Control+z");
      await expectText(page.locator(".cm-content"), /sub_7\([^)]*0\.25, MAX\)/);
      await page.locator(".cm-content").click();
      await page.keyboard.press("Control+End");
      await page.keyboard.type(" oops {");
      await page.getByRole("button", { name: "Apply text to diagram" }).click();
      await expectText(page.locator(".text-toolbar [role=status]"), /^Not applied: \d+ errors?, marked in the text \(line \d+:\d+/);
      await expectVisible(page.locator(".cm-lintRange-error, .cm-lint-marker-error").first());
      await shot("text-error");
      await page.getByRole("button", { name: "Reload saved text" }).click();
      await expectText(page.locator(".text-toolbar [role=status]"), /revision 2/);
    }],

    ["integrator downloads", async () => {
      await view("Sensor integrator");
      await expectVisible(page.getByRole("button", { name: /Download Driver stubs/ }));
      await shot("downloads");
    }],

    ["operator: deploy", async () => {
      await view("Operator");
      await expectVisible(page.getByRole("region", { name: "Deployment history" }));
      await page.getByRole("button", { name: "Deploy revision 2" }).click();
      const result = page.getByTestId("deploy-result");
      await expectVisible(result, 30000);
      const text = await result.textContent();
      if (drone) {
        if (!/Acked/.test(text ?? "")) throw new Error(`deploy not acked: ${text}`);
        await expectText(page.getByRole("region", { name: "Deployment history" }), /acked/);
      } else if (!/Deploy failed/.test(text ?? "")) {
        throw new Error(`without a drone the deploy must fail visibly, got: ${text}`);
      }
      await shot("operator");
    }],

    ["monitor", async () => {
      await view("Scientist");
      await panel("Monitor");
      await expectVisible(page.getByRole("status", { name: "Link status" }));
      await page.getByRole("checkbox", { name: /sub_5/ }).check();
      await expectVisible(page.getByTestId("chart-sub_5"));
      if (drone) {
        // A dynamic subscription: the SubBroker answers ACCEPTED or NOT_AVAILABLE with its reason.
        const form = page.getByRole("form", { name: "Dynamic subscription" });
        await form.getByLabel("Topic").selectOption("usv.accelerometer.accel_x");
        await form.getByLabel("Period (s)").fill("1.0");
        await form.getByLabel("Aggregation").selectOption("AVERAGE");
        await form.getByRole("button", { name: "Ask the drone" }).click();
        await expectText(form.locator(".dynamic-replies li"), /ACCEPTED|NOT_AVAILABLE/, 15000);
      }
      if (drone) await expectText(page.getByRole("status", { name: "Link status" }), /link up/, 20000);
      if (liveValues) await expectText(page.getByTestId("last-sub_5"), /last -?\d/, 30000);
      if (drone && liveValues) {
        // Fill gaps: the drone recomputes what the link missed from its archive; the progress
        // bar runs to done, with no window delivered twice.
        // Here for the whole drone (every subscription); views.mjs fills one chart after an outage.
        const fill = page.getByRole("region", { name: /^Fill gaps: drone / });
        await fill.getByRole("button", { name: "Fill gaps" }).click();
        await expectText(fill.getByTestId("backfill-progress"), /done: \d+ filled, 0 duplicates/, 90000);
        // The operator fills the drone's gaps as the scientist does (the same region in the
        // Operator view; backfill edits no model).
        await view("Operator");
        await panel("Monitor");
        const byOperator = page.getByRole("region", { name: /^Fill gaps: drone / });
        await byOperator.getByRole("button", { name: "Fill gaps" }).click();
        await expectText(byOperator.getByTestId("backfill-progress"), /done: \d+ filled, 0 duplicates/, 90000);
        await view("Scientist");
        await panel("Monitor");
      }
      await page.getByRole("checkbox", { name: /sub_1 / }).uncheck();
      await page.getByRole("checkbox", { name: /sub_2 / }).uncheck();
      await expand(true);
      if (liveValues) await page.waitForTimeout(3000); // a few points on the charts
      await shot("monitor");
      await expand(false);
    }],

    ["3D and archives panels", async () => {
      await panel("3D");
      // viser's developer controls (Save Canvas, Dev Settings) never show, also while it connects:
      // covered until the scene's own panel (the legend) is drawn, then the cover goes.
      const iframe = page.locator('iframe[title="3D scene of the drone"]');
      await iframe.waitFor({ timeout: 15000 });
      const scene = page.frameLocator('iframe[title="3D scene of the drone"]');
      const cover = page.getByRole("status").filter({ hasText: "Connecting to the 3D scene" });
      const t0 = Date.now();
      let covered = 0;
      for (;;) {
        const dev = (await Promise.all(["Save Canvas", "Dev Settings"].map((t) => scene.getByText(t, { exact: true }).first().isVisible().catch(() => false)))).some(Boolean);
        const hidden = await cover.isVisible();
        if (dev && !hidden) throw new Error("viser's developer controls shown to the user");
        covered += hidden ? 1 : 0;
        if (!hidden && await scene.getByText("Drone tracks").isVisible().catch(() => false)) break;
        if (Date.now() - t0 > 30000) throw new Error(`the 3D scene did not show its legend within 30 s (covered: ${hidden})`);
        await page.waitForTimeout(100);
      }
      console.log(`    3D scene: its own panel after ${Date.now() - t0} ms, covered in ${covered} checks`);
      await shot("scene3d");
      await panel("Archives");
      if (liveValues) {
        // The PubBroker's lossless MCAP archive of what the simulated sensors published.
        const files = page.getByRole("table", { name: "Archive files" });
        await expectText(files, /\.mcap/, 15000);
        await files.locator("button.link").first().click();
        await page.getByRole("form", { name: "Plot an archived topic" }).getByRole("button", { name: "Plot" }).click();
        await expectText(page.locator(".archives-panel figcaption"), /usv\.accelerometer\.\w+ \(m\/s²\): \d+ samples/, 15000);
        // The same file served to Foxglove/Lichtblick (seek, play, pause) on the replay port.
        await page.getByRole("button", { name: "Replay in Foxglove", exact: true }).click();
        await expectText(page.getByRole("status", { name: "Foxglove replay" }), /\d+ messages.*ws:\/\/127\.0\.0\.1:\d+/, 15000);
        // Export dataset: the file as the scientist's CSV (modd dataset, run by the backend),
        // downloaded and opened: every sample with its UDUNITS unit (scenario 1 declares no
        // position, so its lat/lon columns are empty; tests/dataset checks positions).
        const exportForm = page.getByRole("form", { name: "Export dataset" });
        await exportForm.getByLabel("Dataset format").selectOption("csv");
        const [download] = await Promise.all([
          page.waitForEvent("download", { timeout: 60000 }),
          exportForm.getByRole("button", { name: "Export", exact: true }).click(),
        ]);
        const rows = readFileSync(await download.path(), "utf8").trim().split("\n");
        if (rows[0] !== '"time","topic","value","unit","lat","lon","alt"') throw new Error(`dataset CSV header: ${rows[0]}`);
        const accel = rows.filter((r) => /"usv\.accelerometer\.accel_[xyz]",-?[0-9.e+-]+,"m s-2"/.test(r));
        if (accel.length < 10) throw new Error(`dataset CSV: ${accel.length} accelerometer rows with their unit (${rows.length} rows; ${rows[1]})`);
        // The base-station record of what was delivered, live and backfilled.
        await expectText(page.getByRole("table", { name: "Base-station record files" }), /\.mcap/, 15000);
        // Export dataset of what the subscribers received: the record's windows, one row per
        // window at its end, named by subscriber, with the unit of its topic.
        await exportForm.getByLabel("Dataset source").selectOption("received");
        const [received] = await Promise.all([
          page.waitForEvent("download", { timeout: 60000 }),
          exportForm.getByRole("button", { name: "Export", exact: true }).click(),
        ]);
        // Named by the backend: the drone, what it holds and the time span.
        if (!/^usv-received-\d{8}T\d{6}Z-\d{8}T\d{6}Z\.csv$/.test(received.suggestedFilename())) throw new Error(`received: ${received.suggestedFilename()}`);
        const windows = readFileSync(await received.path(), "utf8").trim().split("\n");
        const bySubscriber = windows.filter((r) => /^[^,]+,"[A-Za-z_]\w*",(-?[0-9.e+-]+)?,"m s-2"/.test(r));
        if (bySubscriber.length < 3) throw new Error(`received CSV: ${bySubscriber.length} windows of accelerometer subscribers (${windows.length} rows; ${windows[1]})`);
        await expand(true);
      }
      await page.waitForTimeout(500);
      await shot("archives");
      await expand(false);
    }],
  ];
}

/** From any page of the workbench: back to the projects, a model imported as a new project, its diagram open. */
export async function importProject(page, fileName, model) {
  await page.getByRole("button", { name: "MoDD", exact: true }).click().catch(() => undefined);
  await page.getByRole("heading", { name: "MoDD projects" }).waitFor({ state: "visible", timeout: 10000 });
  await page.locator('input[type="file"]').setInputFiles({ name: fileName, mimeType: "application/json", buffer: Buffer.from(JSON.stringify(model)) });
  await page.locator('.react-flow__node[data-id="drone"]').waitFor({ state: "visible", timeout: 20000 });
}

export async function waitUntil(check, timeoutMs, describe) {
  const t0 = Date.now();
  while (Date.now() - t0 < timeoutMs) {
    if (await check()) return;
    await new Promise((r) => setTimeout(r, 200));
  }
  throw new Error(`timed out: ${describe ? await describe() : "condition"}`);
}

export async function expectVisible(locator, timeout = 10000) {
  await locator.waitFor({ state: "visible", timeout });
}

export async function expectText(locator, re, timeout = 10000) {
  await waitUntil(async () => re.test((await locator.first().textContent().catch(() => "")) ?? ""), timeout,
    async () => `${re} not in "${(await locator.first().textContent().catch(() => "")) ?? ""}"`);
}

export async function expectCount(locator, n, timeout = 10000) {
  await waitUntil(async () => (await locator.count()) === n, timeout, async () => `expected ${n} elements, found ${await locator.count()}`);
}

async function expectDisabled(locator) {
  if (!(await locator.isDisabled())) throw new Error("expected a disabled control");
}
