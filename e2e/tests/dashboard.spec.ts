import { expect, test, type Page } from "@playwright/test";
import { open, toScreen, world, type Hooks } from "./helpers";

// The control-station dashboard against the real station. The station is shared by every
// spec of the run: each test puts back what it changed (parameters, e-stop, referee, targets).

/**
 * Fastest visible robot in mm/s, from the positions of two worlds 0.4 s apart: the reported
 * vx/vy of a standing robot are noisy (50-120 mm/s seen in the simulator), positions are not.
 */
async function maxSpeed(page: Page): Promise<number> {
  const w0 = await world(page);
  const t0 = Date.now();
  await new Promise((r) => setTimeout(r, 400)); // the sampling interval of the measurement
  const w1 = await world(page);
  const dt = (Date.now() - t0) / 1000;
  let max = 0;
  for (const r of w1.robots) {
    const p = w0.robots.find((q) => q.team === r.team && q.id === r.id);
    if (p && r.visible && p.visible) max = Math.max(max, Math.hypot(r.x - p.x, r.y - p.y) / dt);
  }
  return max;
}

const FIELD = "strategy.formation_period_s";

test("a parameter changed in one browser shows in another; a bad value shows the server's message", async ({ browser }) => {
  const ctxA = await browser.newContext();
  const ctxB = await browser.newContext();
  const a = await ctxA.newPage();
  const b = await ctxB.newPage();
  const schema = await (await a.request.get("/api/params/schema")).json();
  const def = schema.$defs.StrategyParams.properties.formation_period_s.default as number;
  try {
    for (const p of [a, b]) {
      await p.goto("/");
      await expect(p.getByTestId("connection-status")).toContainText("connected");
      await p.getByTestId("tab-params").click();
    }
    const inA = a.getByTestId(`param-input-${FIELD}`);
    const inB = b.getByTestId(`param-input-${FIELD}`);
    await expect(inB).toHaveValue(def.toFixed(1));
    await inA.fill("7.5");
    await inA.press("Enter");
    await expect(inB).toHaveValue("7.5");
    expect((await (await a.request.get("/api/params")).json()).values.strategy.formation_period_s).toBe(7.5);

    // above the maximum (60): the server refuses, its message shows, the field goes back
    await inA.fill("99");
    await inA.press("Enter");
    await expect(a.getByTestId(`param-error-${FIELD}`)).toContainText(/less than or equal to 60/);
    await expect(inA).toHaveValue("7.5");
    // the API refuses NaN with a message too, and nothing changes
    const nan = await a.request.patch("/api/params", { data: '{"strategy": {"formation_period_s": NaN}}', headers: { "content-type": "application/json" } });
    expect(nan.status()).toBe(422);
    await expect(inB).toHaveValue("7.5");

    // reset to default from page B: page A follows
    await b.getByTestId(`param-reset-${FIELD}`).click();
    await expect(inA).toHaveValue(def.toFixed(1));
  } finally {
    await a.request.patch("/api/params", { data: { strategy: { formation_period_s: def } } });
    await ctxA.close();
    await ctxB.close();
  }
});

test("the station's folders show read-only beside the parameters; an import carrying one is refused with the field named", async ({ page }) => {
  await page.goto("/");
  await expect(page.getByTestId("connection-status")).toContainText("connected");
  await page.getByTestId("tab-params").click();
  const answer = (await (await page.request.get("/api/folders")).json()) as { folders: { name: string; paths: string[] }[] };
  const state = answer.folders.find((f) => f.name === "state_dir")!.paths[0];
  const box = page.getByTestId("station-folders");
  const paths = (name: string) => box.getByTestId(`station-folder-${name}`).getByTestId("station-folder-paths");
  await expect(paths("scripts_dir")).toHaveText(/\/engine_scripts$/);
  await expect(box.getByTestId("station-folder-scripts_dir")).toContainText("--scripts-dir");
  await expect(paths("record_dir")).toHaveText(`${state}/logs`);
  await expect(paths("log_dirs")).toHaveText(/\/tests\/data$/);
  await expect(paths("state_dir")).toHaveText(state);
  await expect(box.locator("input, button, select, textarea")).toHaveCount(0);
  // no form field for a folder (the group's other fields are there)
  await expect(page.getByTestId("param-input-recording.max_mb")).toHaveCount(1);
  await expect(page.getByTestId("param-input-strategy.goalkeeper_function")).toHaveCount(1);
  await expect(page.getByTestId("param-input-recording.folder")).toHaveCount(0);
  await expect(page.getByTestId("param-input-strategy.scripts_dir")).toHaveCount(0);

  // an export from before the folders left the parameters: refused, the server's words shown
  const v0 = (await (await page.request.get("/api/params")).json()).version as number;
  await page.getByTestId("params-import-file").setInputFiles(
    new URL("../../tests/data/state-before-issue30/touchline-params.json", import.meta.url).pathname);
  const alert = page.getByTestId("presets").getByRole("alert");
  await expect(alert).toContainText("strategy.scripts_dir: folders are set when the station starts (--scripts-dir");
  await expect(alert).toContainText("recording.folder: folders are set when the station starts (--record-dir");
  expect((await (await page.request.get("/api/params")).json()).version).toBe(v0);
});

test("a live plot of a robot signal moves", async ({ page }) => {
  await open(page);
  await page.getByTestId("tab-plots").click();
  await page.getByTestId("add-plot").click();
  await page.getByTestId("signal-search").fill("blue 1 speed_mps");
  await page.getByTestId("signal-robot.blue.1.speed_mps").click();
  const lastX = () => page.evaluate(() => {
    const p = (window as unknown as { __touchline: Hooks }).__touchline.plots();
    return p.length ? p[p.length - 1]!.lastX : 0;
  });
  await expect.poll(lastX).toBeGreaterThan(0);
  const first = await lastX();
  await expect.poll(lastX).toBeGreaterThan(first + 0.2);
  const host = page.getByTestId("plot-canvas-host").last();
  const shot1 = await host.screenshot();
  await expect.poll(async () => Buffer.compare(shot1, await host.screenshot())).not.toBe(0);
  // signals are derived from the data: every robot's fields and the health streams are there
  const signals = await page.evaluate(() => (window as unknown as { __touchline: Hooks }).__touchline.signals());
  expect(signals).toContain("robot.yellow.3.x");
  expect(signals).toContain("health.streams.vision.rate_hz");
  // leave no plot behind for the next test (stored in localStorage of this context only)
  await page.getByRole("button", { name: "Remove plot" }).last().click();
});

test("select a robot, drag on the field: it drives there with the dragged heading", async ({ page }) => {
  await open(page);
  await page.getByTestId("robot-row-blue-4").click();
  await expect(page.getByTestId("selected-robot")).toContainText("blue 4");
  const target = { x: 1200, y: -1500 };
  const p = await toScreen(page, target.x, target.y);
  await page.mouse.move(p.x, p.y);
  await page.mouse.down();
  await page.mouse.move(p.x, p.y - 30, { steps: 4 }); // up on the screen: +y in the world, heading pi/2
  await page.mouse.move(p.x, p.y - 60, { steps: 4 });
  await page.mouse.up();
  try {
    // the demo gives robot 4 a target too: wait for the operator's one
    await expect.poll(async () => (await world(page)).robots.find((r) => r.team === "blue" && r.id === 4)?.target?.source ?? null)
      .toBe("operator");
    const t = (await world(page)).robots.find((r) => r.team === "blue" && r.id === 4)!.target!;
    expect(Math.abs(t.orientation! - Math.PI / 2)).toBeLessThan(0.15);
    expect(Math.hypot(t.x - target.x, t.y - target.y)).toBeLessThan(40);
    await expect.poll(async () => {
      const r = (await world(page)).robots.find((rr) => rr.team === "blue" && rr.id === 4)!;
      return Math.hypot(r.x - target.x, r.y - target.y);
    }, { timeout: 30_000, intervals: [250] }).toBeLessThan(150);
  } finally {
    await page.request.delete("/api/robots/blue/4/target", { headers: { "X-Touchline": "1" } });
  }
});

test("emergency stop (key E) stops every robot; Release lets them go", async ({ page }) => {
  await open(page);
  await expect.poll(() => maxSpeed(page), { timeout: 20_000 }).toBeGreaterThan(100); // the demo moves them
  try {
    await page.getByTestId("field-canvas").hover();
    await page.keyboard.press("e");
    await expect(page.getByTestId("estop-button")).toHaveAttribute("data-active", "true");
    await expect.poll(() => maxSpeed(page), { timeout: 5_000, intervals: [200] }).toBeLessThan(60);
    // releasing asks first: "Keep stopped" keeps it, "Release" releases it
    await page.getByTestId("estop-button").click();
    await expect(page.getByTestId("estop-release-dialog")).toBeVisible();
    await page.getByTestId("estop-release-cancel").click();
    await expect(page.getByTestId("estop-release-dialog")).toHaveCount(0);
    await expect(page.getByTestId("estop-button")).toHaveAttribute("data-active", "true");
    // the Health tab says the stop is active and latched in the relay as well
    await page.getByTestId("tab-health").click();
    await expect(page.getByTestId("health-estop")).toHaveAttribute("data-active", "true");
    await expect(page.getByTestId("health-estop")).toHaveAttribute("data-relay-latched", "true", { timeout: 5_000 });
    await expect(page.getByTestId("health-warnings")).toContainText("emergency stop active since");
    // a release without the operator's confirmation is refused, with the reason
    const refused = await page.request.post("/api/estop", { data: { active: false } });
    expect(refused.status()).toBe(409);
    expect(await refused.text()).toContain("confirm");
    await page.getByTestId("estop-button").click();
    await page.getByTestId("estop-release-confirm").click();
    await expect(page.getByTestId("estop-button")).toHaveAttribute("data-active", "false");
  } finally {
    await page.request.post("/api/estop", { data: { active: false, confirm: true } });
  }
  expect((await world(page)).estop).toBe(false);
});

test("internal referee: HALT stops the robots, FORCE START resumes", async ({ page }) => {
  await open(page);
  await page.getByTestId("tab-referee").click();
  try {
    await page.getByTestId("ref-HALT").click();
    await expect(page.getByTestId("referee-command")).toHaveText("HALT");
    await expect(page.getByTestId("referee-source")).toContainText("internal");
    await expect.poll(() => maxSpeed(page), { timeout: 5_000, intervals: [200] }).toBeLessThan(60);
    await page.getByTestId("ref-FORCE_START").click();
    await expect(page.getByTestId("referee-command")).toHaveText("FORCE_START");
    await expect.poll(async () => (await world(page)).referee?.command).toBe("FORCE_START");
    await expect.poll(() => maxSpeed(page), { timeout: 20_000 }).toBeGreaterThan(100);
    // an unknown command: 422 with the server's message
    const bad = await page.request.post("/api/referee/internal/command", { data: { command: "DANCE" } });
    expect(bad.status()).toBe(422);
  } finally {
    await page.request.post("/api/referee/internal/command", { data: { command: "FORCE_START" } });
    // the station keeps acting on the last referee message it heard: let FORCE_START arrive
    // before the internal referee goes quiet, or the robots stay halted
    await expect.poll(async () => (await world(page)).referee?.command).toBe("FORCE_START");
    await page.request.post("/api/referee/internal/enabled", { data: { enabled: false } });
  }
});

test("field: wheel zooms, F fits; right-click teleports the ball", async ({ page }) => {
  await open(page);
  const before = await toScreen(page, 1000, 0);
  const centre = await toScreen(page, 0, 0);
  await page.mouse.move(centre.x, centre.y);
  await page.mouse.wheel(0, -400);
  await expect.poll(async () => (await toScreen(page, 1000, 0)).x - centre.x).toBeGreaterThan((before.x - centre.x) * 1.3);
  await page.keyboard.press("f");
  await expect.poll(async () => Math.round((await toScreen(page, 1000, 0)).x)).toBe(Math.round(before.x));

  const spot = { x: -1000, y: 800 };
  const s = await toScreen(page, spot.x, spot.y);
  try {
    await page.mouse.click(s.x, s.y, { button: "right" });
    await page.getByTestId("menu-teleport-ball").click();
    await expect.poll(async () => {
      const b = (await world(page)).ball;
      return b ? Math.hypot(b.x - spot.x, b.y - spot.y) : 1e9;
    }, { timeout: 5_000 }).toBeLessThan(60);
  } finally {
    await page.request.post("/api/sim/ball", { data: { x: 0, y: 0 } });
  }
});

// The README's pictures (only with TOUCHLINE_DOCS_SHOTS=1: the config leaves out the "docs:"
// tests otherwise; 1280x720): the station as a newcomer first sees it, with today's top bar
// and blue 1 selected, driving to an operator's target; then the Health tab.
test("docs: screenshots of the station and its health", async ({ page }) => {
  await open(page);
  if (await page.getByTestId("name-prompt").isVisible()) await page.getByTestId("name-save").click();
  await page.getByTestId("robot-row-blue-1").click();
  const p = await toScreen(page, 1500, 1500);
  try {
    await page.mouse.click(p.x, p.y);
    await expect.poll(async () => (await world(page)).robots.find((r) => r.team === "blue" && r.id === 1)?.target?.source ?? null)
      .toBe("operator");
    await expect.poll(() => maxSpeed(page), { timeout: 10_000 }).toBeGreaterThan(100);
    await page.mouse.move(0, 0);
    await page.screenshot({ path: new URL("../../docs/screenshot.png", import.meta.url).pathname });
    await page.getByTestId("tab-health").click();
    await expect(page.getByTestId("health-estop")).toBeVisible();
    await page.mouse.move(0, 0);
    await page.screenshot({ path: new URL("../../docs/screenshot-health.png", import.meta.url).pathname });
  } finally {
    await page.request.delete("/api/robots/blue/1/target", { headers: { "X-Touchline": "1" } });
  }
});
