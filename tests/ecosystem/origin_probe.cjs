// What a web page can read from WebSocket servers: headless Chromium (Debian's
// /usr/bin/chromium through playwright-core) opens PAGE, and the page opens
// each socket of the list, counting the frames it receives and noting whether
// it opened, for SECONDS. Prints one JSON report: {name: {opened, frames, code}}.
// With LOGIN (BASE USER PASSWORD), the browser first signs in to the workbench
// (the session cookie, as an operator who has the workbench open).
//   node origin_probe.cjs PAGE SECONDS '[{"name": .., "url": .., "protocols": [..]}]' [LOGIN]
"use strict";
const { chromium } = require("playwright-core");

async function main() {
  const [page, seconds, list, base, user, password] = process.argv.slice(2);
  const browser = await chromium.launch({
    executablePath: process.env.MODD_CHROMIUM ?? "/usr/bin/chromium",
    headless: true,
    args: ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
      "--disable-background-networking"],
  });
  try {
    const tab = await browser.newPage();
    if (base) {
      const login = await tab.request.post(base + "/api/auth/login",
        { data: { username: user, password, session: "cookie" } });
      if (login.status() !== 200) throw new Error(`login: ${login.status()}`);
    }
    await tab.goto(page);
    const report = await tab.evaluate(async ([sockets, ms]) => {
      const out = {};
      for (const s of sockets) {
        const seen = { opened: false, frames: 0, code: null };
        out[s.name] = seen;
        try {
          const ws = new WebSocket(s.url, s.protocols);
          ws.onopen = () => { seen.opened = true; };
          ws.onmessage = () => { seen.frames += 1; };
          ws.onclose = (e) => { seen.code = e.code; };
        } catch (e) {
          seen.code = String(e).slice(0, 200);
        }
      }
      await new Promise((resolve) => setTimeout(resolve, ms));
      return out;
    }, [JSON.parse(list), Number(seconds) * 1000]);
    console.log(JSON.stringify(report));
  } finally {
    await browser.close();
  }
}

main().catch((e) => { console.log(JSON.stringify({ fatal: String(e) })); process.exit(1); });
