// Field canvas frame rate with 4 live plots open, in headless Chromium (numbers, not a test).
//
//   node bench/page_fps.mjs [--seconds 10] [--plots 4] [--port 18950]
//
// Starts an isolated station with 11 v 11 robots, opens the page at 1280x720, opens the
// Plots tab with N plots (2 robot signals + 1 health signal each), then counts over the
// window the field's requestAnimationFrame callbacks and the ones that drew (via
// window.__touchline.stats()), and the plot redraws. Stops the station at the end.

import { spawn } from "node:child_process";
import { tmpdir } from "node:os";
import { dirname, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { chromium } from "@playwright/test";

const root = resolve(dirname(fileURLToPath(import.meta.url)), "..");
const arg = (name, def) => {
  const i = process.argv.indexOf(`--${name}`);
  return i > 0 ? Number(process.argv[i + 1]) : def;
};
const seconds = arg("seconds", 10);
const nPlots = arg("plots", 4);
const port = arg("port", 18900 + (process.pid % 90));

function startStation() {
  const proc = spawn(
    ".venv/bin/python",
    ["-m", "launcher", "--isolated", "--port", String(port), "--sim-arg=--blue=11", "--sim-arg=--yellow=11"],
    { cwd: root, stdio: ["ignore", "pipe", "pipe"], detached: false },
  );
  return new Promise((resolveUrl, reject) => {
    let out = "";
    const timer = setTimeout(() => reject(new Error(`station did not start:\n${out.slice(-2000)}`)), 60_000);
    const onData = (d) => {
      out += d.toString();
      const m = /TOUCHLINE_READY (\S+)/.exec(out);
      if (m) {
        clearTimeout(timer);
        resolveUrl({ proc, url: m[1] });
      }
    };
    proc.stdout.on("data", onData);
    proc.stderr.on("data", (d) => (out += d.toString()));
    proc.on("exit", (code) => reject(new Error(`station exited (${code}):\n${out.slice(-2000)}`)));
  });
}

async function stopStation(proc) {
  if (proc.exitCode !== null) return;
  proc.kill("SIGTERM");
  await new Promise((r) => {
    const t = setTimeout(() => {
      proc.kill("SIGKILL");
      r();
    }, 10_000);
    proc.on("exit", () => {
      clearTimeout(t);
      r();
    });
  });
}

const { proc, url } = await startStation();
let browser;
try {
  browser = await chromium.launch({
    executablePath: process.env.CHROMIUM_PATH ?? "/usr/bin/chromium",
    args: ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run"],
  });
  const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
  await page.goto(url);
  await page.getByTestId("connection-status").filter({ hasText: "connected" }).waitFor();
  await page.waitForFunction(() => (window.__touchline?.getWorld()?.robots.length ?? 0) >= 22, null, { timeout: 30_000 });

  // Baseline: no plots.
  const measure = async (s) => {
    const a = await page.evaluate(() => window.__touchline.stats());
    await page.waitForTimeout(s * 1000); // the measurement window itself
    const b = await page.evaluate(() => window.__touchline.stats());
    const dt = (b.t - a.t) / 1000;
    return {
      seconds: +dt.toFixed(2),
      field_raf_per_s: +((b.fieldRafs - a.fieldRafs) / dt).toFixed(1),
      field_draws_per_s: +((b.fieldDraws - a.fieldDraws) / dt).toFixed(1),
      plot_draws_per_s: +((b.plotDraws - a.plotDraws) / dt).toFixed(1),
      world_rows_per_s: +((b.sampleRows - a.sampleRows) / dt).toFixed(1),
    };
  };
  const baseline = await measure(Math.min(5, seconds));

  await page.getByTestId("tab-plots").click();
  const picks = [
    ["blue 1 speed_mps", "robot.blue.1.speed_mps"],
    ["blue 1 command forward", "robot.blue.1.command.forward_mps"],
    ["yellow 7 x", "robot.yellow.7.x"],
    ["ball x", "ball.x"],
    ["blue 9 y", "robot.blue.9.y"],
    ["vision rate", "health.streams.vision.rate_hz"],
    ["latency p99", "health.latency.p99_ms"],
    ["control measured", "health.processors.control.measured_hz"],
  ];
  for (let i = 0; i < nPlots; i++) {
    await page.getByTestId("add-plot").click();
    for (const [q, key] of [picks[(2 * i) % picks.length], picks[(2 * i + 1) % picks.length]]) {
      const plot = page.locator('[data-testid^="plot-"][data-keys]').last();
      if ((await plot.getByTestId("signal-search").count()) === 0) await plot.getByTestId("plot-add-signal").click();
      await plot.getByTestId("signal-search").fill(q);
      await plot.getByTestId(`signal-${key}`).click();
    }
  }
  await page.waitForFunction((n) => window.__touchline.plots().length >= n, nPlots);
  const withPlots = await measure(seconds);
  const plots = await page.evaluate(() => window.__touchline.plots().map((p) => ({ keys: p.keys, points: p.points })));
  await page.screenshot({ path: `${tmpdir()}/touchline_page_fps.png` }).catch(() => {});
  const refreshHz = await page.evaluate(
    () =>
      new Promise((r) => {
        let n = 0;
        const t0 = performance.now();
        const f = () => (++n < 60 ? requestAnimationFrame(f) : r((1000 * n) / (performance.now() - t0)));
        requestAnimationFrame(f);
      }),
  );
  console.log(JSON.stringify({ robots: 22, display_raf_hz: +refreshHz.toFixed(1), baseline_no_plots: baseline, with_plots: { plots: nPlots, ...withPlots }, plots }, null, 2));
} finally {
  await browser?.close();
  await stopStation(proc);
}
