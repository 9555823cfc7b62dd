// Opens the proxied 3D scene in headless Chromium (Debian's /usr/bin/chromium
// through playwright-core) with a cookie session, and prints one JSON report:
// HTTP status, the page's CSP, whether viser's client connected its
// WebSocket through the proxy, CSP refusals in the console, page errors.
//   node scene_browser.cjs BASE USER PASSWORD
"use strict";
const { chromium } = require("playwright-core");
const { mkdtempSync, rmSync } = require("node:fs");
const { tmpdir } = require("node:os");
const { join } = require("node:path");

async function main() {
  const [base, user, password] = process.argv.slice(2);
  const profile = mkdtempSync(join(tmpdir(), "modd-scene-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.MODD_CHROMIUM ?? "/usr/bin/chromium",
    headless: true,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--use-gl=swiftshader",
      "--enable-unsafe-swiftshader", "--no-first-run", "--disable-background-networking"],
  });
  const report = { status: 0, csp: "", connected: false, frames: 0, refused: [], errors: [], devControls: null };
  try {
    const page = await context.newPage();
    page.on("console", (m) => {
      const text = m.text();
      if (text.startsWith("Connected!")) report.connected = true;
      if (/Content Security Policy/i.test(text)) report.refused.push(text.slice(0, 400));
    });
    page.on("pageerror", (e) => report.errors.push(String(e).slice(0, 400)));
    page.on("websocket", (ws) => ws.on("framereceived", () => { report.frames += 1; }));
    await page.goto(base + "/api/health");
    const login = await page.request.post(base + "/api/auth/login",
      { data: { username: user, password, session: "cookie" } });
    if (login.status() !== 200) throw new Error(`login: ${login.status()}`);
    const resp = await page.goto(base + "/scene/");
    report.status = resp.status();
    report.csp = resp.headers()["content-security-policy"] ?? "";
    const deadline = Date.now() + 30000;
    while (Date.now() < deadline && !(report.connected && report.frames > 0)) {
      await page.waitForTimeout(250);
    }
    await page.waitForTimeout(1000);
    // viser's developer controls (Save Canvas, Dev Settings) are not for users
    report.devControls = [];
    for (const text of ["Save Canvas", "Dev Settings", "Share"]) {
      if (await page.getByText(text, { exact: true }).first().isVisible().catch(() => false)) report.devControls.push(text);
    }
  } finally {
    await context.close().catch(() => undefined);
    rmSync(profile, { recursive: true, force: true });
  }
  console.log(JSON.stringify(report));
}

main().catch((e) => { console.log(JSON.stringify({ fatal: String(e) })); process.exit(1); });
