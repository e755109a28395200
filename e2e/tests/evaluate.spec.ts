import { expect, test } from "@playwright/test";
import { open } from "./helpers";

// The Evaluate tab against the real station: the "quick" suite (tests/evaluate/quick, given
// to the launcher with --suite-dir: three short headless runs, one of which fails its checks)
// started from the tab, its progress followed in the page, the failed scenario opened in the
// replay timeline. The station is shared by every spec: the test leaves it live.

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
    await expect(page.locator(".app")).toHaveAttribute("data-replaying", "true", { timeout: 30_000 });
    await expect(page.getByTestId("timeline-bar")).toBeVisible();
    const p = await (await page.request.get("/api/player")).json();
    expect(p.source).toBe("log");
    expect(p.file).toMatch(/quick_goal\.log$/);
    expect(p.duration_s).toBeGreaterThan(4);
    expect(p.duration_s).toBeLessThan(5);
  });
});
