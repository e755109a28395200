import { execFile } from "node:child_process";
import { rmSync } from "node:fs";
import { join } from "node:path";
import { promisify } from "node:util";
import { expect, test, type Page } from "@playwright/test";
import { open } from "./helpers";

// The Evaluate tab against the real station: the "quick" suite (tests/evaluate/quick, given
// to the launcher with --suite-dir: three short headless runs, one of which fails its checks)
// started from the tab, its progress followed in the page, the failed scenario opened in the
// replay timeline; the class folder (--class-dir tests/evaluate/class) graded from the tab;
// a match series written by `python -m evaluate` into the station's reports folder, read in
// the tab. The station is shared by every spec: each test leaves it live.

const ROOT = new URL("../..", import.meta.url).pathname;
const run = promisify(execFile);

async function waitForTimeline(page: Page, file: RegExp) {
  await expect(page.locator(".app")).toHaveAttribute("data-replaying", "true", { timeout: 30_000 });
  await expect(page.getByTestId("timeline-bar")).toBeVisible();
  const p = await (await page.request.get("/api/player")).json();
  expect(p.source).toBe("log");
  expect(p.file).toMatch(file);
  return p as { duration_s: number };
}

test.afterEach(async ({ request }) => {
  await request.post("/api/player", { data: { action: "live" }, headers: { "Content-Type": "application/json" } });
});

test("start a suite, watch its progress, replay a failed scenario", async ({ page }) => {
  test.setTimeout(240_000);
  await open(page);
  await page.getByTestId("tab-evaluate").click();
  const panel = page.getByTestId("evaluate-panel");
  await expect(panel).toBeVisible();
  await page.getByTestId("eval-suite").selectOption("quick");
  await expect(panel).toContainText("scenarios in quick");

  await test.step("start it: the progress bar follows the runs as they come back", async () => {
    await page.getByTestId("eval-start").click();
    const job = page.getByTestId("eval-job");
    await expect(job).toHaveAttribute("data-state", "running");
    await expect(page.getByTestId("eval-progress-text")).toContainText("quick: ");
    await expect(job).toHaveAttribute("data-state", "done", { timeout: 180_000 });
    await expect(page.getByTestId("eval-progress-text")).toContainText("3/3 · 2 passed · 1 failed");
    await expect(page.getByTestId("eval-progress")).toHaveAttribute("value", "3");
  });

  await test.step("the report: every run with its checks, the failed one marked", async () => {
    const report = page.getByTestId("eval-report");
    await expect(report).toBeVisible();
    await expect(page.getByTestId("eval-run-quick_goal")).toContainText("fail");
    await expect(page.getByTestId("eval-run-quick_goal")).toContainText("collision");
    await expect(page.getByTestId("eval-run-quick_keeper#1")).toContainText("pass");
    await page.getByTestId("eval-failed-only").check();
    await expect(page.locator('[data-testid^="eval-run-"]')).toHaveCount(1);
  });

  await test.step("replay the failed scenario: the timeline opens on its log", async () => {
    await page.getByTestId("eval-replay-quick_goal").click();
    const p = await waitForTimeline(page, /quick_goal\.log$/);
    expect(p.duration_s).toBeGreaterThan(4);
    expect(p.duration_s).toBeLessThan(5);
  });
});

test("grade the class: the grade table, a crashing student's run replayed", async ({ page }) => {
  test.setTimeout(240_000);
  await open(page);
  await page.getByTestId("tab-evaluate").click();
  await page.getByTestId("eval-suite").selectOption("class_suite");
  await page.getByTestId("eval-class").click();
  const job = page.getByTestId("eval-job");
  await expect(page.getByTestId("eval-progress-text")).toContainText("class · class_suite");
  await expect(job).toHaveAttribute("data-state", "done", { timeout: 180_000 });
  await expect(page.getByTestId("eval-progress-text")).toContainText("3/3 · 1 passed · 2 failed");
  const grades = page.getByTestId("eval-grades");
  await expect(grades).toBeVisible();
  await expect(page.getByTestId("eval-grade-good")).toContainText("1.00");
  await expect(page.getByTestId("eval-grade-good").locator(".eval-pass")).toHaveCount(1);
  for (const who of ["crash", "spin"]) await expect(page.getByTestId(`eval-grade-${who}`).locator(".eval-fail")).toHaveCount(1);
  // why it failed, in the cell's note and in the run's row
  await expect(page.getByTestId("eval-run-crash.drive")).toContainText("ZeroDivisionError");
  await page.getByTestId("eval-cell-replay-crash-drive").click();
  await waitForTimeline(page, /crash\/drive\.log$/);
});

test("a match series from python -m evaluate: listed, its verdict, a match replayed", async ({ page, request }) => {
  test.setTimeout(240_000);
  const folders = await (await request.get("/api/folders")).json();
  const reports: string = folders.folders.find((f: { name: string }) => f.name === "reports_dir").paths[0];
  const name = `e2e-matches-${Date.now()}`;
  const out = join(reports, name);
  try {
    // two short matches of the match play against the simple one, sides swapped, on 2 workers
    await run(
      join(ROOT, ".venv/bin/python"),
      ["-m", "evaluate", "matches", "--a", "match", "--b", "simple", "--matches", "2", "--half-s", "2", "--no-interludes", "--cameras", "2", "--workers", "2", "--out", out],
      { cwd: ROOT, timeout: 200_000 },
    );
    await open(page);
    await page.getByTestId("tab-evaluate").click();
    await page.getByTestId("eval-refresh").click();
    const row = page.getByTestId(`eval-report-${name}`);
    await expect(row).toContainText("2 matches");
    await row.click();
    const report = page.getByTestId("eval-report");
    await expect(report).toContainText("A:match against B:simple: 2 matches");
    await expect(page.getByTestId("eval-verdict")).toContainText(/significant|no decided match/);
    for (const m of ["match-001", "match-002"]) {
      await expect(page.getByTestId(`eval-run-${m}`)).toContainText(/A:match \d+ : \d+ B:simple|B:simple \d+ : \d+ A:match/);
    }
    await page.getByTestId("eval-replay-match-002").click();
    await waitForTimeline(page, /match-002\.log$/);
  } finally {
    rmSync(out, { recursive: true, force: true });
  }
});
