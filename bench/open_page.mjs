// Keeps Touchline's page open in headless Chromium for a while (bench/loop_bench.py --browser):
// the page renders the field and streams the websocket like an operator's browser would.
//
//   node bench/open_page.mjs URL SECONDS
//
// Prints "PAGE_OPEN" once the page has its first world, then waits SECONDS and exits.

import { chromium } from "@playwright/test";

const [url, seconds] = [process.argv[2], Number(process.argv[3] ?? "30")];
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  args: ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
  await page.goto(url);
  await page.waitForSelector("canvas", { timeout: 30_000 });
  console.log("PAGE_OPEN");
  await page.waitForTimeout(seconds * 1000);
} finally {
  await browser.close();
}
