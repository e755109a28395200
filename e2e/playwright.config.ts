import { cpSync, mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { defineConfig } from "@playwright/test";

// The end-to-end tests run against the real three processes (fieldsim, larcmacs_relay,
// backend) started by the launcher on free, non-standard ports, so they never disturb a
// station already running on this machine.
// Chosen once in the runner process; workers inherit it through the environment.
process.env.E2E_PORT ??= String(18000 + (process.pid % 1000));
const port = Number(process.env.E2E_PORT);
const baseURL = `http://127.0.0.1:${port}`;
// The station's team folder: a copy of the shipped team/ (the team-code spec writes and edits
// its files; the repository's own stay as they are), removed when the run ends.
if (!process.env.E2E_TEAM_DIR) {
  const dir = mkdtempSync(join(tmpdir(), "touchline-e2e-team-"));
  cpSync(new URL("../team", import.meta.url).pathname, dir, { recursive: true });
  process.env.E2E_TEAM_DIR = dir;
  process.on("exit", () => rmSync(dir, { recursive: true, force: true }));
}
const teamDir = process.env.E2E_TEAM_DIR;

export default defineConfig({
  testDir: "tests",
  // "docs:" tests write the pictures of docs/ (TOUCHLINE_DOCS_SHOTS=1 npm run test:e2e)
  grepInvert: process.env.TOUCHLINE_DOCS_SHOTS ? undefined : /docs: /,
  timeout: 60_000,
  expect: { timeout: 15_000 },
  fullyParallel: false,
  workers: 1,
  retries: 0,
  reporter: [["list"]],
  outputDir: "test-results",
  use: {
    baseURL,
    viewport: { width: 1280, height: 720 },
    screenshot: "only-on-failure",
    trace: "off",
    launchOptions: {
      executablePath: process.env.CHROMIUM_PATH ?? "/usr/bin/chromium",
      args: [
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
      ],
    },
  },
  webServer: {
    // --log-dir: the replay spec opens the recorded fixture (tests/data) from the Logs dialog.
    // --suite-dir, --class-dir: the Evaluate spec runs the quick suite (tests/evaluate/quick) and
    // grades the test class (tests/evaluate/class: a good, a crashing and a spinning student).
    command: `.venv/bin/python -m launcher --isolated --port ${port} --log-dir tests/data --team-dir ${JSON.stringify(teamDir)} --suite-dir tests/evaluate --class-dir tests/evaluate/class`,
    cwd: "..",
    url: `${baseURL}/api/health`,
    timeout: 60_000,
    reuseExistingServer: false,
    stdout: "pipe",
    stderr: "pipe",
    gracefulShutdown: { signal: "SIGTERM", timeout: 10_000 },
  },
});
