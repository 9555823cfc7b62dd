/**
 * The workbench as people use it (issue "never lose an edit, work
 * together safely"): two people on one project, the revision history, a
 * reload with unsaved edits, deep links, the text view round trip, typing in
 * the inspector, the operator view. Runs after the journey (or alone with
 * MODD_E2E_ONLY=collab); each step fails on the workbench before the change
 * it checks.
 *
 * The second person works in a second browser (own profile, own cookie).
 */
import { join } from "node:path";
import { launch } from "./browser.mjs";
import { waitUntil } from "./journey.mjs";

export function collaboration({ page, baseUrl, password, imagesDir, ports, drone, onCleanup }) {
  let api; // bearer-token client of the admin (set up by the first step)
  let other; // the second person's page
  let pid; // the shared project
  const shot = (p, name) => p.screenshot({ path: join(imagesDir, `${name}.png`) });
  const node = (p, id) => p.locator(`.react-flow__node[data-id="${id}"]`);
  const inspector = (p) => p.getByRole("region", { name: "Inspector" });
  const field = (p, path) => inspector(p).locator(`[data-field="${path}"]`).locator("input, select").first();
  const select = async (p, id) => { await node(p, id).click(); await inspector(p).locator("h2").first().waitFor(); };
  const setText = async (p, path, value) => { const f = field(p, path); await f.fill(value); await f.press("Enter"); };
  const save = (p) => p.getByRole("button", { name: "Save", exact: true }).click();
  const openProject = async (p, name) => {
    await p.goto(baseUrl);
    await p.getByRole("button", { name, exact: true }).click();
    await node(p, "drone").waitFor();
  };
  const login = async (p, user, pw) => {
    await p.goto(baseUrl);
    await p.getByLabel("User name").fill(user);
    await p.getByLabel("Password").fill(pw);
    await p.getByRole("button", { name: "Log in" }).click();
    await p.getByRole("heading", { name: "MoDD projects" }).waitFor();
  };

  return [
    ["collab: two people, one project — live notice, conflict banner, three-way merge", async () => {
      api = await tokenClient(baseUrl, "admin", password);
      await api("POST", "/api/users", { username: "alice", password: "alice-password-1", roles: ["scientist"] });
      pid = (await api("POST", "/api/projects", { name: "shared", model: { model: scenario1(ports) }, message: "created" })).id;
      if (!(await page.getByRole("heading", { name: "MoDD projects" }).count())) {
        await page.goto(baseUrl);
        if (await page.getByLabel("User name").count()) await login(page, "admin", password);
      }
      const second = await launch();
      onCleanup(() => second.close());
      other = second.context.pages()[0] ?? await second.context.newPage();
      await login(other, "alice", "alice-password-1");
      await openProject(page, "shared");
      await openProject(other, "shared");
      await page.getByRole("tab", { name: "Scientist", exact: true }).click();
      // I change sub_1 and sub_2; alice changes sub_1 differently and sub_3, and saves first.
      await select(page, "sub:sub_1");
      await setText(page, "periodS", "8.0");
      await select(page, "sub:sub_2");
      await field(page, "aggregation").selectOption("MAX");
      await select(other, "sub:sub_1");
      await setText(other, "periodS", "4.0");
      await select(other, "sub:sub_3");
      await field(other, "aggregation").selectOption("MIN");
      await save(other);
      await expectText(other.locator(".topbar .revision"), /^r2(?!.*unsaved)/);
      // announced live to me, over the stream socket
      await expectText(page.getByRole("status").filter({ hasText: "Saved by alice" }), /revision 2/);
      await save(page);
      const banner = page.getByRole("alertdialog", { name: "Edit conflict" });
      await expectText(banner, /Revision 2 was saved by alice/);
      const row = banner.locator('tr[data-pointer="/subscribers/sub_1/periodS"]');
      // named in the model's words, not by JSON pointer
      await expectText(row, /^subscriber sub_1: period/);
      await expectText(row, /8\.0 s/);
      await expectText(row, /4\.0 s/);
      if (/\/subscribers\//.test((await banner.textContent()) ?? "")) throw new Error("the merge view shows JSON pointers");
      const merge = banner.getByRole("button", { name: /Merge into revision 2/ });
      if (!(await merge.isDisabled())) throw new Error("merging before the conflicting field is chosen");
      await shot(page, "conflict-banner");
      await row.getByRole("radio").first().check(); // keep mine: 8.0
      await merge.click();
      await expectText(page.locator(".topbar .revision"), /r2 · unsaved/);
      await save(page);
      await expectText(page.locator(".topbar .revision"), /^r3(?!.*unsaved)/);
      const r3 = (await api("GET", `/api/projects/${pid}/model`)).model;
      const sub = (n) => r3.subscribers.find((s) => s.name === n);
      if (sub("sub_1").periodS !== "8.0" || sub("sub_2").aggregation !== "MAX" || sub("sub_3").aggregation !== "MIN") {
        throw new Error(`merge lost an edit: ${JSON.stringify(r3.subscribers.slice(0, 3))}`);
      }
    }],

    ["collab: revision history — compare two, restore as a new revision, redeploy a past one", async () => {
      const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
      await panel("History");
      const table = page.getByRole("table", { name: "Revisions" });
      await expectText(table, /r3 \(open\)/);
      await table.getByLabel("Pick revision 1").check();
      await table.getByLabel("Pick revision 3").check();
      await page.getByRole("button", { name: "Compare r1 → r3" }).click();
      const diff = page.getByLabel("Changes from revision 1 to 3");
      await expectText(diff, /~ subscriber sub_1: period 2\.0 s → 8\.0 s/);
      await expectText(diff, /~ subscriber sub_3: aggregation AVERAGE → MIN/);
      await shot(page, "history");
      page.once("dialog", (d) => void d.accept());
      await table.locator('tr[data-revision="1"]').getByRole("button", { name: "Restore" }).click();
      await expectText(page.getByRole("status").filter({ hasText: "restored" }), /Revision 1 restored as revision 4/);
      await expectText(page.locator(".topbar .revision"), /^r4(?!.*unsaved)/);
      const r4 = (await api("GET", `/api/projects/${pid}/model`)).model;
      if (r4.subscribers[0].periodS !== "2.0" || r4.subscribers[2].aggregation !== "AVERAGE") throw new Error("r4 is not r1's model");
      if (drone) {
        await page.getByRole("tab", { name: "Operator", exact: true }).click();
        await panel("History");
        page.once("dialog", (d) => void d.accept());
        await page.getByRole("table", { name: "Revisions" }).locator('tr[data-revision="2"]').getByRole("button", { name: "Redeploy" }).click();
        await expectText(page.getByRole("status").filter({ hasText: "Revision 2" }), /Revision 2 deployed to usv \(acked\)/, 30000);
        const last = (await api("GET", `/api/projects/${pid}/deployments`))[0];
        if (last.revision !== 2 || last.status !== "acked") throw new Error(`last deployment: ${JSON.stringify(last)}`);
      }
    }],

    ["collab: deep links, unsaved edits survive a reload, leaving warns", async () => {
      await page.goto(`${baseUrl}/projects/${pid}/scientist/history`);
      await page.getByRole("table", { name: "Revisions" }).waitFor();
      if ((await page.getByRole("tab", { name: "Scientist", exact: true }).getAttribute("aria-selected")) !== "true") throw new Error("the deep link's view is not open");
      await select(page, "sub:sub_1");
      await setText(page, "periodS", "0.5");
      await expectText(page.locator(".topbar .revision"), /unsaved/);
      await page.waitForTimeout(500); // the draft is written 0.3 s after the last edit
      let warned = null;
      page.once("dialog", (d) => { warned = d.type(); void d.accept(); });
      await page.reload();
      if (warned !== "beforeunload") throw new Error(`leaving with unsaved edits did not warn (${warned})`);
      await expectText(page.getByRole("status").filter({ hasText: "restored from this browser" }), /Unsaved edits of revision 4 restored/);
      await expectText(page.locator(".topbar .revision"), /^r4 · unsaved/);
      if (new URL(page.url()).pathname !== `/projects/${pid}/scientist/history`) throw new Error(`the address is ${page.url()}`);
      await select(page, "sub:sub_1");
      if ((await field(page, "periodS").inputValue()) !== "0.5") throw new Error("the unsaved edit was lost");
      await shot(page, "draft-restored");
      await save(page);
      await expectText(page.locator(".topbar .revision"), /^r5(?!.*unsaved)/);
      await page.waitForTimeout(500);
      // this project's draft (other projects of the run may keep theirs)
      const left = await page.evaluate((p) => Object.keys(window.localStorage).filter((k) => k.startsWith("modd.draft.") && k.endsWith(`.${p}`)), pid);
      if (left.length) throw new Error(`a saved draft is still kept: ${left}`);
      // A link opened in a browser not logged in: the login, then that project, view and panel.
      const third = await launch();
      onCleanup(() => third.close());
      const p3 = third.context.pages()[0] ?? await third.context.newPage();
      await p3.goto(`${baseUrl}/projects/${pid}/operator/deploy`);
      await p3.getByLabel("User name").fill("admin");
      await p3.getByLabel("Password").fill(password);
      await p3.getByRole("button", { name: "Log in" }).click();
      await node(p3, "drone").waitFor();
      if ((await p3.getByRole("tab", { name: "Operator", exact: true }).getAttribute("aria-selected")) !== "true") throw new Error("the link's view is not open after login");
      if ((await p3.getByRole("tab", { name: "Deploy", exact: true }).getAttribute("aria-selected")) !== "true") throw new Error("the link's panel is not open after login");
      // and a second tab of the same browser shares the session (cookie), no new login
      const tab = await third.context.newPage();
      await tab.goto(`${baseUrl}/projects/${pid}`);
      await node(tab, "drone").waitFor();
      await third.close();
    }],

    ["collab: text view — unchanged text applies in every view after inspector edits (\"5\" is 5.0)", async () => {
      const panel = (name) => page.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
      await page.getByRole("tab", { name: "Scientist", exact: true }).click();
      await select(page, "sub:sub_2");
      await setText(page, "periodS", "5");
      if ((await field(page, "periodS").inputValue()) !== "5.0") throw new Error("a typed period is not stored in its one spelling");
      for (const view of ["System designer", "Sensor integrator", "Scientist"]) {
        await page.getByRole("tab", { name: view, exact: true }).click();
        await panel("Text");
        const apply = page.getByRole("button", { name: "Apply text to diagram" });
        await apply.waitFor();
        await page.waitForTimeout(400); // the text follows the diagram's unsaved edits
        const validated = page.waitForResponse((r) => r.url().endsWith("/api/validate"));
        await apply.click();
        await validated;
        await page.waitForTimeout(200);
        const notice = page.locator(".notice");
        if (await notice.count()) throw new Error(`Apply of the unchanged text in the ${view} view: ${await notice.textContent()}`);
      }
      await expectText(page.locator(".topbar .revision"), /unsaved/);
      await save(page);
      await expectText(page.locator(".topbar .revision"), /^r6(?!.*unsaved)/);
    }],

    ["collab: a whole model pasted in the Text panel — applied for the admin in the scientist view, refused in words for a scientist", async () => {
      const panel = (p, name) => p.getByRole("tablist").last().getByRole("tab", { name, exact: true }).click();
      // The saved model with its sensor renamed: a change to the sensors, the publishers and the subscriptions.
      const saved = (await api("GET", `/api/projects/${pid}/model`)).model;
      const whole = JSON.stringify(saved, null, 2).replaceAll("accelerometer", "imu");
      const paste = async (p) => {
        await panel(p, "Text");
        await p.getByRole("button", { name: "Apply text to diagram" }).waitFor();
        await p.waitForTimeout(400);
        await p.locator(".cm-content").click();
        await p.keyboard.press("Control+a");
        await p.keyboard.insertText(whole);
        await p.getByRole("button", { name: "Apply text to diagram" }).click();
      };
      await page.getByRole("tab", { name: "Scientist", exact: true }).click();
      await paste(page);
      await expectText(page.locator(".text-toolbar [role=status]"), /^Applied to the diagram\./);
      await node(page, "sensor:imu").waitFor();
      await shot(page, "text-pasted");
      await page.locator(".react-flow__pane").click({ position: { x: 8, y: 8 } });
      await page.keyboard.press("Control+z"); // one undo step takes the whole model back
      await node(page, "sensor:accelerometer").waitFor();
      await other.goto(`${baseUrl}/projects/${pid}/scientist/text`);
      await paste(other);
      const status = other.locator(".text-toolbar [role=status]");
      await expectText(status, /This model changes the sensors and the publishers, which your roles \(scientist\) may not change\./);
      await expectText(status, /Ask a user with the designer or integrator role \(or an admin\).*import it as a new project/);
      if (/\/drone|\/publishers/.test((await status.textContent()) ?? "")) throw new Error("the refusal names JSON pointers");
      await node(other, "sensor:accelerometer").waitFor();
      await shot(other, "text-refused");
    }],

    ["collab: inspector — applies as you type, and the first click after a rename (accepted or refused) is kept", async () => {
      await page.getByRole("tab", { name: "Scientist", exact: true }).click();
      await select(page, "sub:sub_4");
      const period = field(page, "periodS");
      await period.click();
      await period.press("Control+A");
      await period.pressSequentially("1.5", { delay: 60 });
      // no Enter, no blur: the diagram and the plan follow once typing pauses
      await expectText(node(page, "sub:sub_4"), /1\.5 s/, 5000);
      if (!(await period.evaluate((el) => el === document.activeElement))) throw new Error("the field lost the focus");
      await select(page, "sub:sub_3");
      const name = field(page, "name");
      await name.fill("renamed_3");
      await node(page, "sub:sub_2").click(); // at once, while the rename is still being typed
      await expectText(inspector(page).locator("h2").first(), /sub_2$/);
      await node(page, "sub:renamed_3").waitFor();
      // typing a name keeps the focus while the element is renamed under it
      await select(page, "sub:renamed_3");
      await field(page, "name").click();
      await field(page, "name").press("End");
      await field(page, "name").pressSequentially("_x", { delay: 60 });
      await node(page, "sub:renamed_3_x").waitFor({ timeout: 5000 });
      await page.waitForTimeout(300);
      await field(page, "name").pressSequentially("y", { delay: 60 });
      await node(page, "sub:renamed_3_xy").waitFor({ timeout: 5000 });
      // A rename typed, then a press on another node held across the moment the rename applies
      // (the diagram re-renders under the pointer): the click still selects that node.
      await field(page, "name").pressSequentially("z", { delay: 30 });
      const box = await node(page, "sub:sub_2").boundingBox();
      await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
      await page.mouse.down();
      await page.waitForTimeout(700);
      await page.mouse.up();
      await node(page, "sub:renamed_3_xyz").waitFor({ timeout: 5000 });
      await expectText(inspector(page).locator("h2").first(), /sub_2$/);
      // A rename the view refuses (the integrator's sensor rename would rewrite the subscriptions):
      // its notice, shown on blur, must not move the diagram under the click that caused the blur.
      await page.getByRole("tab", { name: "Sensor integrator", exact: true }).click();
      await select(page, "sensor:accelerometer");
      await field(page, "name").fill("imu");
      await node(page, "sub:sub_2").click();
      await expectText(page.locator(".notice"), /which the integrator view may not change/);
      await expectText(inspector(page).locator("h2").first(), /sub_2$/);
      await select(page, "sensor:accelerometer");
      const shown = await field(page, "name").inputValue();
      if (shown !== "accelerometer") throw new Error(`the refused name stays in the field: "${shown}"`);
      await page.locator(".notice").getByRole("button", { name: "Dismiss" }).click();
      await page.getByRole("tab", { name: "Scientist", exact: true }).click();
      await save(page);
      await expectText(page.locator(".topbar .revision"), /^r7(?!.*unsaved)/);
    }],

    ["collab: operator view — no undo, copy or delete; the palette follows the view", async () => {
      await page.getByRole("tab", { name: "Scientist", exact: true }).click();
      await select(page, "sub:sub_2");
      await setText(page, "periodS", "3");
      await save(page); // an edit saved, then undone from the Operator view would vanish locally
      await expectText(page.locator(".topbar .revision"), /^r8(?!.*unsaved)/);
      await page.getByRole("tab", { name: "Operator", exact: true }).click();
      const palette = page.getByRole("navigation", { name: "Palette" });
      await node(page, "sub:sub_2").click();
      for (const name of ["Undo", "Copy", "Delete", "Paste", "+ Subscriber"]) {
        if (!(await palette.getByRole("button", { name, exact: true }).isDisabled())) throw new Error(`${name} is enabled in the Operator view`);
      }
      if (await page.getByRole("form", { name: "Quick subscription" }).count()) throw new Error("the quick subscription is offered in the Operator view");
      await page.keyboard.press("Control+z");
      await page.keyboard.press("Delete");
      await node(page, "sub:sub_2").waitFor();
      await expectText(node(page, "sub:sub_2"), /every 3\.0 s/);
      if (/unsaved/.test((await page.locator(".topbar .revision").textContent()) ?? "")) throw new Error("the Operator view changed the model");
      // back in the Scientist view the palette offers its commands again
      await page.getByRole("tab", { name: "Scientist", exact: true }).click();
      if (await palette.getByRole("button", { name: "Undo", exact: true }).isDisabled()) throw new Error("Undo is off in the Scientist view");
      await page.getByRole("form", { name: "Quick subscription" }).waitFor();
    }],

    ["/docs works offline (Swagger UI served by the backend)", async () => {
      const foreign = [];
      const p = await page.context().newPage();
      await p.route((url) => !url.href.startsWith(baseUrl), (r) => { foreign.push(r.request().url()); return r.abort(); });
      await p.goto(`${baseUrl}/docs`);
      await expectText(p.locator(".swagger-ui .info .title"), /MoDD workbench/, 15000);
      await p.locator(".swagger-ui .opblock").first().waitFor();
      await p.close();
      if (foreign.length) throw new Error(`/docs asked the network for ${foreign.join(", ")}`);
    }],

    ["admin: users and roles in the browser — create, set roles, reset a password, delete", async () => {
      await page.goto(baseUrl);
      await page.getByRole("button", { name: "Users and roles" }).click();
      const form = page.getByRole("form", { name: "New user" });
      await form.getByLabel("User name").fill("bob");
      await form.getByLabel("Password").fill("bob-password-1");
      await form.getByLabel("scientist").uncheck();
      await form.getByLabel("integrator").check();
      await form.getByRole("button", { name: "Create user" }).click();
      await expectText(page.getByRole("status"), /bob created/);
      const users = page.getByRole("table", { name: "Users" });
      await users.getByLabel("bob operator").check();
      await expectText(page.getByRole("status"), /bob: roles saved/);
      const bob = (await api("GET", "/api/users")).find((u) => u.username === "bob");
      if (bob.roles.slice().sort().join(",") !== "integrator,operator") throw new Error(`bob's roles: ${bob.roles}`);
      await shot(page, "users");
      page.once("dialog", (d) => void d.accept("bob-password-2"));
      await users.locator('tr[data-user="bob"]').getByRole("button", { name: "Reset password" }).click();
      await expectText(page.getByRole("status"), /bob: password reset/);
      await tokenClient(baseUrl, "bob", "bob-password-2"); // the new password works
      page.once("dialog", (d) => void d.accept());
      await users.locator('tr[data-user="bob"]').getByRole("button", { name: "Delete" }).click();
      await expectText(page.getByRole("status"), /bob deleted/);
      if ((await api("GET", "/api/users")).some((u) => u.username === "bob")) throw new Error("bob was not deleted");
      await page.getByRole("button", { name: "Projects" }).click();
      await page.getByRole("heading", { name: "MoDD projects" }).waitFor();
    }],

    ["diagram: auto-layout fits clear of the minimap, new nodes appear in view, names legible zoomed out", async () => {
      await page.goto(`${baseUrl}/projects/${pid}/scientist/plan`);
      await node(page, "drone").waitFor();
      const overlap = (a, b) => a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;
      const underMinimap = async () => {
        const mini = await page.locator(".react-flow__minimap").boundingBox();
        const hit = [];
        for (const n of await page.locator(".react-flow__node").all()) {
          const b = await n.boundingBox();
          if (b && overlap(b, mini)) hit.push(await n.getAttribute("data-id"));
        }
        return hit;
      };
      await page.getByRole("button", { name: "Auto-layout" }).click();
      await page.waitForTimeout(900);
      const hidden = await underMinimap();
      if (hidden.length) throw new Error(`after auto-layout, under the minimap: ${hidden.join(", ")}`);
      // zoomed in on a corner, a new subscriber still shows up where it can be seen
      for (let i = 0; i < 4; i++) await page.locator(".react-flow__controls-zoomin").click();
      await page.waitForTimeout(300);
      const before = await page.locator(".react-flow__node").count();
      await page.getByRole("navigation", { name: "Palette" }).getByRole("button", { name: "+ Subscriber" }).click();
      await waitUntil(async () => (await page.locator(".react-flow__node").count()) === before + 1, 5000);
      await page.waitForTimeout(500);
      const fresh = page.locator(".react-flow__node.selected");
      const canvas = await page.locator(".canvas").boundingBox();
      const b = await fresh.boundingBox();
      if (!b || b.x < canvas.x || b.y < canvas.y || b.x + b.width > canvas.x + canvas.width || b.y + b.height > canvas.y + canvas.height) {
        throw new Error(`the new node is out of view: ${JSON.stringify(b)} in ${JSON.stringify(canvas)}`);
      }
      await page.keyboard.press("Control+z");
      // zoomed far out: names only, larger
      for (let i = 0; i < 8; i++) await page.locator(".react-flow__controls-zoomout").click();
      await page.locator(".canvas.canvas-far").waitFor();
      if (await page.locator(".react-flow__node .node-detail").first().isVisible()) throw new Error("details still shown zoomed out");
      await page.getByRole("button", { name: "Zoom to fit" }).click();
      await page.waitForTimeout(500);
      const again = await underMinimap();
      if (again.length) throw new Error(`after zoom to fit, under the minimap: ${again.join(", ")}`);
      // Names legible (11 px on screen, 10.5 at least) at fit-to-screen and zoomed out to about half.
      const legible = async (what) => {
        const r = await page.evaluate(() => {
          const zoom = new DOMMatrix(getComputedStyle(document.querySelector(".react-flow__viewport")).transform).a;
          const px = [...document.querySelectorAll(".react-flow__node .node-label")].map((l) => parseFloat(getComputedStyle(l).fontSize) * zoom);
          return { zoom, min: Math.min(...px) };
        });
        if (!(r.min >= 10.5)) throw new Error(`${what}: names drawn at ${r.min.toFixed(1)} px on screen (zoom ${r.zoom.toFixed(2)})`);
        return r.zoom;
      };
      await legible("at fit-to-screen");
      for (let i = 0; i < 10 && (await legible("zooming out")) > 0.55; i++) {
        await page.locator(".react-flow__controls-zoomout").click();
        await page.waitForTimeout(250);
      }
      await legible("zoomed out to about half");
      await page.getByRole("button", { name: "Zoom to fit" }).click();
      await page.waitForTimeout(500);
    }],

    ["new project from a template, with a first step per role view", async () => {
      await page.goto(baseUrl);
      await page.getByLabel("Project name").fill("from template");
      await page.getByLabel("Start from").selectOption("scenario1");
      await page.getByRole("button", { name: "Create" }).click();
      await node(page, "sub:sub_7").waitFor();
      for (const [view, re] of [["System designer", /PubBroker/], ["Scientist", /Quick subscription/], ["Operator", /Deploy panel/]]) {
        await page.getByRole("tab", { name: view, exact: true }).click();
        const note = page.getByRole("note", { name: "First step" });
        await expectText(note, re);
        await note.getByRole("button", { name: "Got it" }).click();
        if (await note.count()) throw new Error(`the ${view} first step stays after "Got it"`);
      }
    }],

    ["names-only mode: sub_7 and accel_x keep their underscores whole at fit-to-screen", async () => {
      await page.getByRole("tab", { name: "System designer", exact: true }).click();
      await page.getByRole("button", { name: "Zoom to fit" }).click();
      await page.locator(".canvas.canvas-far").waitFor();
      await page.waitForTimeout(500);
      for (const name of ["sub_7", "accel_x"]) {
        const label = page.locator(".react-flow__node .node-label", { hasText: new RegExp(`^${name}$`) }).first();
        const { drawn, whole } = await underscoreInk(page, label);
        // the underscore's ink as drawn, against the same name unclipped (tall line, nothing hidden)
        if (!(drawn >= 0.9 * whole && whole > 0)) throw new Error(`${name}: ${Math.round((100 * drawn) / whole)} % of its underscore is drawn (reads "${name.replace("_", " ")}")`);
      }
    }],
  ];
}

/** A bearer-token API client (the admin's set-up calls). */
export async function tokenClient(baseUrl, username, password) {
  const res = await fetch(`${baseUrl}/api/auth/login`, {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify({ username, password }),
  });
  if (!res.ok) throw new Error(`login ${username}: HTTP ${res.status}`);
  const { token } = await res.json();
  return async (method, path, json) => {
    const r = await fetch(`${baseUrl}${path}`, {
      method, headers: { Authorization: `Bearer ${token}`, ...(json ? { "Content-Type": "application/json" } : {}) },
      body: json ? JSON.stringify(json) : undefined,
    });
    if (!r.ok) throw new Error(`${method} ${path}: HTTP ${r.status} ${await r.text()}`);
    return r.status === 204 ? null : r.json();
  };
}

/**
 * How much of the first "_" of a label is drawn: the label's picture with the
 * underscore, less the picture with it hidden (the same layout); and the same
 * with the label unclipped. Changes the label's DOM for a moment and puts back
 * its own nodes.
 */
async function underscoreInk(page, label) {
  const variant = (hide, free) => label.evaluate((l, [hide, free]) => {
    l.__own ??= [...l.childNodes];
    const text = l.__own.map((n) => n.textContent).join("");
    const i = text.indexOf("_");
    const gap = Object.assign(document.createElement("span"), { textContent: "_" });
    gap.style.visibility = "hidden";
    l.replaceChildren(...(hide ? [text.slice(0, i), gap, text.slice(i + 1)] : l.__own));
    l.style.cssText = free ? "overflow: visible; display: block; line-height: 2; padding: 0" : "";
  }, [hide, free]);
  const shots = [];
  for (const [hide, free] of [[false, false], [true, false], [false, true], [true, true]]) {
    await variant(hide, free);
    shots.push((await label.screenshot()).toString("base64"));
  }
  await variant(false, false);
  const [drawn, whole] = await page.evaluate(async (shots) => {
    const pixels = async (s) => {
      const img = new Image();
      img.src = `data:image/png;base64,${s}`;
      await img.decode();
      const c = Object.assign(document.createElement("canvas"), { width: img.width, height: img.height });
      const ctx = c.getContext("2d");
      ctx.drawImage(img, 0, 0);
      return ctx.getImageData(0, 0, img.width, img.height).data;
    };
    const diff = async (a, b) => {
      const [p, q] = [await pixels(a), await pixels(b)];
      let sum = 0;
      for (let i = 0; i < Math.min(p.length, q.length); i++) if (i % 4 !== 3) sum += Math.abs(p[i] - q[i]);
      return sum;
    };
    return [await diff(shots[0], shots[1]), await diff(shots[2], shots[3])];
  }, shots);
  return { drawn, whole };
}

async function expectText(locator, re, timeout = 10000) {
  await waitUntil(async () => re.test((await locator.first().textContent().catch(() => "")) ?? ""), timeout,
    async () => `${re} not in "${(await locator.first().textContent().catch(() => "")) ?? ""}"`);
}

/** Scenario 1 on the drone "usv" (the simulated drone's name), zenoh delivery. */
function scenario1(ports) {
  const t = (v) => `usv.accelerometer.${v}`;
  const subs = [["accel_x", "2.0", "AVERAGE"], ["accel_y", "2.0", "AVERAGE"], ["accel_x", "0.25", "AVERAGE"],
    ["accel_y", "0.25", "AVERAGE"], ["accel_z", "0.25", "MIN"], ["accel_z", "0.25", "MAX"], ["accel_z", "0.25", "MAX"]];
  return {
    schemaVersion: "1.0",
    drone: { name: "usv", sensors: [{ name: "accelerometer", variables: ["accel_x", "accel_y", "accel_z"].map((name) => ({ name, unit: "METER_PER_SECOND_SQUARED" })) }] },
    pubBroker: { endpoint: { host: "127.0.0.1", port: ports.pub }, logPath: "/tmp/modd/logs" },
    subBroker: { endpoint: { host: "127.0.0.1", port: ports.sub }, configPath: "/tmp/modd/conf" },
    publishers: [{ name: "pub_1", periodS: "0.04", topics: [t("accel_x"), t("accel_y"), t("accel_z")] }],
    subscribers: subs.map(([v, periodS, aggregation], i) => ({ name: `sub_${i + 1}`, topic: t(v), periodS, aggregation })),
  };
}
