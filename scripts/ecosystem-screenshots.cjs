/**
 * Screenshots of Lichtblick on MoDD's Foxglove servers (docs/ecosystem.md),
 * driven by scripts/ecosystem-screenshots.sh:
 *
 *   node scripts/ecosystem-screenshots.cjs DIST WORK OUT LIVE_WS
 *
 * DIST is the built Lichtblick web app, served here on a free loopback port
 * together with WORK/modd-layout.json (the project's layout, downloaded by
 * the scientist), WORK/archive.mcap (the drone's archive, recovered) and
 * WORK/modd-archive-layout.json (plots of the archive's topics). Lichtblick opens them from its own URL parameters
 * (`ds=...&ds.url=...&layoutUrl=...`), which is what a person does through
 * Open connection (or Open file) and Layouts > Import from file. Headless
 * Debian Chromium through playwright-core (NODE_PATH=frontend/node_modules).
 */
"use strict";
const fs = require("node:fs");
const http = require("node:http");
const os = require("node:os");
const path = require("node:path");
const { chromium } = require("playwright-core");

const [dist, work, out, liveWs] = process.argv.slice(2);
const TYPES = {
  ".html": "text/html", ".js": "text/javascript", ".css": "text/css", ".json": "application/json",
  ".wasm": "application/wasm", ".svg": "image/svg+xml", ".png": "image/png", ".woff2": "font/woff2",
  ".ttf": "font/ttf", ".ico": "image/x-icon", ".map": "application/json",
};

/** The app's files and the two layouts, on 127.0.0.1 only; nothing outside DIST or WORK. */
function serve() {
  const server = http.createServer((req, res) => {
    const url = new URL(req.url, "http://x");
    let file;
    if (url.pathname.startsWith("/modd/")) {
      file = path.join(work, path.basename(url.pathname));
    } else {
      const rel = path.normalize(decodeURIComponent(url.pathname)).replace(/^([/\\])+/, "");
      file = path.join(dist, rel || "index.html");
      if (!file.startsWith(path.resolve(dist))) file = path.join(dist, "index.html");
    }
    if (!fs.existsSync(file) || fs.statSync(file).isDirectory()) file = path.join(dist, "index.html");
    const size = fs.statSync(file).size;
    const headers = {
      "content-type": TYPES[path.extname(file)] ?? "application/octet-stream",
      // as Lichtblick's own web server (cross-origin isolation)
      "cross-origin-opener-policy": "same-origin",
      "cross-origin-embedder-policy": "credentialless",
      "accept-ranges": "bytes", // Lichtblick reads a remote MCAP file by ranges
    };
    const range = /^bytes=(\d+)-(\d*)$/.exec(req.headers.range ?? "");
    if (range) {
      const start = Number(range[1]);
      const end = Math.min(range[2] ? Number(range[2]) : size - 1, size - 1);
      if (start > end) {
        res.writeHead(416, { "content-range": `bytes */${size}` }).end();
        return;
      }
      res.writeHead(206, { ...headers, "content-range": `bytes ${start}-${end}/${size}`,
        "content-length": end - start + 1 });
      if (req.method === "HEAD") res.end();
      else fs.createReadStream(file, { start, end }).pipe(res);
      return;
    }
    res.writeHead(200, { ...headers, "content-length": size });
    if (req.method === "HEAD") res.end();
    else fs.createReadStream(file).pipe(res);
  });
  return new Promise((resolve) => server.listen(Number(process.env.MODD_APP_PORT || 0), "127.0.0.1", () => resolve(server)));
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function shot(page, name, clip) {
  const file = path.join(out, name);
  await page.screenshot({ path: file, clip });
  console.log(`ecosystem-screenshots: ${file}`);
}

async function main() {
  const server = await serve();
  const app = `http://127.0.0.1:${server.address().port}`;
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), "modd-lichtblick-"));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.MODD_CHROMIUM ?? "/usr/bin/chromium",
    headless: true,
    viewport: { width: 1600, height: 1000 },
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync",
      "--use-gl=swiftshader", "--enable-unsafe-swiftshader"],
  });
  try {
    const page = context.pages()[0] ?? (await context.newPage());
    page.on("pageerror", (e) => console.error(`page error: ${e.message}`));

    // 1. What a person does first: Open connection > Foxglove WebSocket > the URL make run printed.
    await page.goto(app + "/");
    const dialog = page.getByTestId("DataSourceDialog");
    await dialog.getByText("Open connection").click({ timeout: 60_000 });
    await page.getByText("Foxglove WebSocket", { exact: true }).first().click({ force: true });
    const urlField = page.getByRole("textbox").first();
    await urlField.fill(liveWs);
    await sleep(500);
    await shot(page, "ecosystem-lichtblick-open-connection.png");

    // 2. Live, with the project's layout: plots per subscriber, map, link status.
    const live = `${app}/?ds=foxglove-websocket&ds.url=${encodeURIComponent(liveWs)}` +
      `&layoutUrl=${encodeURIComponent(app + "/modd/modd-layout.json")}`;
    await page.goto(live);
    await sleep(Number(process.env.LIVE_WAIT_MS ?? 45_000));
    await shot(page, "ecosystem-lichtblick-live.png");
    // The map and the link status, each full screen (the panel's menu > Fullscreen).
    // (the map panel without the app bar; the table's one row at the top of the page)
    const map = { x: 0, y: 44, width: 1600, height: 870 };
    const top = { x: 0, y: 0, width: 1600, height: 190 };
    for (const [id, name, zoomIn, clip] of [[/ map!/, "map", 4, map], [/ Table!/, "link-table", 0, top]]) {
      const panel = page.getByTestId(id).first();
      if (!(await panel.count())) {
        console.error(`ecosystem-screenshots: no panel ${id}`);
        continue;
      }
      await panel.hover();
      await panel.getByTestId("panel-menu").first().click();
      await page.getByTestId("panel-menu-fullscreen").first().click();
      await sleep(1_000);
      for (let i = 0; i < zoomIn; i++) {
        await page.getByRole("button", { name: "Zoom in" }).first().click();
        await sleep(300);
      }
      await sleep(Number(process.env.PANEL_WAIT_MS ?? 10_000));
      await shot(page, `ecosystem-lichtblick-${name}.png`, clip);
      await page.keyboard.press("Escape");
      await sleep(500);
    }

    // 3. The drone's archive, opened as a file (Lichtblick's Remote file, an
    // MCAP read by HTTP ranges): its plots hold the whole recording; then a
    // seek to its middle and play.
    const replay = `${app}/?ds=remote-file&ds.url=${encodeURIComponent(app + "/modd/archive.mcap")}` +
      `&layoutUrl=${encodeURIComponent(app + "/modd/modd-archive-layout.json")}`;
    await page.goto(replay);
    await sleep(Number(process.env.REPLAY_WAIT_MS ?? 30_000));
    const scrubber = page.getByTestId("playback-slider").first();
    if (await scrubber.count()) {
      const box = await scrubber.boundingBox();
      if (box) await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
    } else {
      console.error("ecosystem-screenshots: no playback scrubber");
    }
    const play = page.getByTestId("play-button").first();
    if (await play.count()) await play.click();
    await sleep(5_000);
    await shot(page, "ecosystem-lichtblick-archive.png");

    // 4. The workbench's "Replay in Foxglove" with "play at once": the backend's
    // replay server plays the archive's range when Lichtblick subscribes.
    const replayUrl = fs.readFileSync(path.join(work, "replay-url"), "utf8").trim();
    await page.goto(`${app}/?ds=foxglove-websocket&ds.url=${encodeURIComponent(replayUrl)}` +
      `&layoutUrl=${encodeURIComponent(app + "/modd/modd-archive-layout.json")}`);
    await sleep(Number(process.env.REPLAY_WAIT_MS ?? 30_000));
    await shot(page, "ecosystem-lichtblick-replay.png");
  } finally {
    await context.close().catch(() => undefined);
    fs.rmSync(profile, { recursive: true, force: true });
    server.close();
  }
}

main().catch((e) => {
  console.error(e);
  process.exit(1);
});
