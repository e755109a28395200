import { expect, test, type Page } from "@playwright/test";
import { open, toScreen, type Hooks, type World } from "./helpers";

// The log player against the real station: the recorded 2.5 s fieldsim session in tests/data
// (4 cameras, 12 robots, STOP at ~0.5 s, FORCE_START at ~1.1 s) opened from the Logs dialog
// (the launcher gets --log-dir tests/data). The station is shared by every spec: each test
// leaves it live.

const FIXTURE = "fieldsim-2s.log.gz";
/** One camera frame at 60 Hz, in s (4 cameras: a vision record every ~4 ms). */
const FRAME_S = 1 / 60;

interface PlayerEvent { t_s: number; kind: string; label: string }
interface Player {
  source: "live" | "log"; file: string | null; duration_s: number; position_s: number; playing: boolean;
  speed: number; loading: number | null; error: string; events: PlayerEvent[]; epoch: number;
}
interface ReplayWorld extends World {
  replay: { position_s: number; duration_s: number; playing: boolean; epoch: number } | null;
  recorded: { source: string; ball: { x: number; y: number } | null; robots: { team: string; id: number; x: number; y: number }[] } | null;
}

async function player(page: Page): Promise<Player> {
  const r = await page.request.get("/api/player");
  expect(r.ok()).toBeTruthy();
  return (await r.json()) as Player;
}

async function replayWorld(page: Page): Promise<ReplayWorld> {
  const r = await page.request.get("/api/world");
  expect(r.ok()).toBeTruthy();
  return (await r.json()) as ReplayWorld;
}

async function postPlayer(page: Page, body: object) {
  return page.request.post("/api/player", { data: body, headers: { "Content-Type": "application/json" } });
}

/** The position the timeline shows ("m:ss.t / m:ss"), in s (floored to tenths by the page). */
async function shownPosition(page: Page): Promise<number> {
  const text = (await page.getByTestId("timeline-position").textContent()) ?? "";
  const m = /(\d+):(\d+)\.(\d)/.exec(text);
  expect(m, `timeline position "${text}"`).not.toBeNull();
  return Number(m![1]) * 60 + Number(m![2]) + Number(m![3]) / 10;
}

/** The station's playhead with the wall time it was read at (midpoint of the request), s. */
async function sample(page: Page): Promise<{ wall: number; pos: number; playing: boolean }> {
  const t0 = performance.now();
  const p = await player(page);
  const t1 = performance.now();
  return { wall: (t0 + t1) / 2000, pos: p.position_s, playing: p.playing };
}

/** Clicks the timeline bar at `fraction` of its width and waits for the station to take the seek. */
async function clickBar(page: Page, fraction: number): Promise<void> {
  const bar = page.getByTestId("timeline-bar");
  const box = (await bar.boundingBox())!;
  const epoch = (await player(page)).epoch;
  await bar.click({ position: { x: box.width * fraction, y: box.height / 2 } });
  await expect.poll(async () => (await player(page)).epoch).toBeGreaterThan(epoch);
}

/** Robots of today's estimate farther than `tol` mm from the same robot recorded in the log. */
function offRecorded(w: ReplayWorld, tol: number): string[] {
  const bad: string[] = [];
  for (const r of w.robots) {
    const rec = w.recorded?.robots.find((q) => q.team === r.team && q.id === r.id);
    if (!rec) bad.push(`${r.team} ${r.id}: not in the recorded estimate`);
    else {
      const d = Math.hypot(r.x - rec.x, r.y - rec.y);
      if (d > tol) bad.push(`${r.team} ${r.id}: ${d.toFixed(1)} mm off`);
    }
  }
  return bad;
}

const hooks = (page: Page) =>
  page.evaluate(() => ({ recordedDrawn: (window as unknown as { __touchline: Hooks }).__touchline.stats().recordedDrawn }));

/** Opens the fixture from the Logs dialog and waits until it is loaded and shown. */
async function openFixture(page: Page): Promise<Player> {
  await page.getByTestId("open-log").click();
  await expect(page.getByTestId("logs-dialog")).toBeVisible();
  await page.getByTestId(`log-open-${FIXTURE}`).click();
  await expect(page.getByTestId("replay-badge")).toBeVisible();
  await expect(page.getByTestId("timeline")).toBeVisible();
  await expect(page.getByTestId("logs-dialog")).toBeHidden();
  await expect.poll(async () => (await player(page)).loading).toBeNull();
  const p = await player(page);
  expect(p.source).toBe("log");
  expect(p.file).toContain(FIXTURE);
  expect(p.error).toBe("");
  return p;
}

test.afterEach(async ({ request }) => {
  await request.post("/api/player", { data: { action: "live" }, headers: { "Content-Type": "application/json" } });
});

test("replaying the fixture: open, seek, play 2x, step, jump, keyboard, back to live", async ({ page }) => {
  test.setTimeout(120_000);
  await open(page);
  await expect(page.getByTestId("replay-badge")).toHaveCount(0);
  await expect(page.locator(".app")).not.toHaveClass(/replaying/);

  let p: Player;
  await test.step("open the log from the Logs dialog", async () => {
    p = await openFixture(page);
    expect(p.duration_s).toBeGreaterThan(2);
    expect(p.duration_s).toBeLessThan(3);
    await expect(page.getByTestId("replay-badge")).toContainText("REPLAY");
    await expect(page.getByTestId("replay-badge")).toContainText(FIXTURE);
    await expect(page.locator(".app")).toHaveClass(/replaying/);
    await expect(page.locator(".app")).toHaveAttribute("data-replaying", "true");
    expect(p.events.filter((e) => e.kind === "command").length).toBeGreaterThanOrEqual(2);
    await expect(page.locator('[data-testid="timeline-marker"][data-kind="command"]').first()).toBeVisible();
    await expect(page.getByTestId("timeline-marker")).toHaveCount(p.events.length);
  });

  await test.step("seek by clicking the bar at 60 %: the page and the station agree, the robots are where the log has them", async () => {
    await clickBar(page, 0.6);
    const want = 0.6 * p.duration_s;
    const got = await player(page);
    expect(got.playing).toBe(false);
    expect(Math.abs(got.position_s - want)).toBeLessThanOrEqual(2 * FRAME_S);
    await expect.poll(() => shownPosition(page)).toBeCloseTo(Math.floor(got.position_s * 10 + 1e-6) / 10, 5);
    await expect(page.getByTestId("timeline-bar")).toHaveAttribute("aria-valuenow", String(Math.round(got.position_s * 10) / 10));
    // the world of this seek (its epoch), today's estimate within 30 mm of the recorded one
    await expect(async () => {
      const w = await replayWorld(page);
      expect(w.replay?.epoch).toBe(got.epoch);
      expect(Math.abs(w.replay!.position_s - got.position_s)).toBeLessThan(1e-3);
      expect(w.recorded, "world.recorded in replay").not.toBeNull();
      expect(w.robots.length).toBe(12);
      expect(w.recorded!.robots.length).toBe(12);
      expect(offRecorded(w, 30)).toEqual([]);
      const worst = Math.max(...w.robots.map((r) => {
        const q = w.recorded!.robots.find((x) => x.team === r.team && x.id === r.id)!;
        return Math.hypot(r.x - q.x, r.y - q.y);
      }));
      test.info().annotations.push({ type: "largest offset from the recorded estimate (mm)", description: worst.toFixed(1) });
    }).toPass({ timeout: 15_000 });
    // the recorded estimate is drawn (12 robots and the ball), with its legend in the layer list
    await expect.poll(async () => (await hooks(page)).recordedDrawn).toBeGreaterThanOrEqual(12);
    await page.getByTestId("layers-toggle").click();
    await expect(page.getByTestId("layer-toggle-recorded")).toBeChecked();
    await expect(page.getByTestId("recorded-legend")).toBeVisible();
    await page.getByTestId("layer-toggle-recorded").click();
    await expect.poll(async () => (await hooks(page)).recordedDrawn).toBe(0);
    await page.getByTestId("layer-toggle-recorded").click();
    await expect.poll(async () => (await hooks(page)).recordedDrawn).toBeGreaterThanOrEqual(12);
    await page.getByTestId("layers-toggle").click();
  });

  await test.step("play at 2x: the log advances about twice as fast as the wall clock", async () => {
    await clickBar(page, 0.04); // room for > 1 s of wall time at 2x
    await page.getByTestId("timeline-speed").selectOption("2");
    await page.getByTestId("timeline-play").click();
    await expect(page.getByTestId("timeline")).toHaveAttribute("data-playing", "true");
    await expect.poll(async () => (await player(page)).speed).toBe(2);
    const first = await sample(page);
    expect(first.playing).toBe(true);
    const shown0 = await shownPosition(page);
    let last = first;
    // sample until 0.6 s of wall time went by (or the log ended)
    await expect.poll(async () => {
      last = await sample(page);
      return last.wall - first.wall >= 0.6 || !last.playing;
    }, { intervals: [50] }).toBe(true);
    expect(last.playing, "the log must not end within the measurement").toBe(true);
    const rate = (last.pos - first.pos) / (last.wall - first.wall);
    test.info().annotations.push({ type: "replay rate at 2x", description: rate.toFixed(2) });
    expect(rate).toBeGreaterThan(1.3);
    expect(rate).toBeLessThan(3);
    await expect.poll(() => shownPosition(page)).toBeGreaterThan(shown0);
  });

  await test.step("pause, one frame forward and one back: about one camera frame each", async () => {
    await page.getByTestId("timeline-play").click();
    await expect(page.getByTestId("timeline")).toHaveAttribute("data-playing", "false");
    const paused = await player(page);
    expect(paused.playing).toBe(false);
    expect(paused.position_s).toBeLessThan(paused.duration_s - 0.1);

    await page.getByTestId("timeline-step-forward").click();
    await expect.poll(async () => (await player(page)).position_s).toBeGreaterThan(paused.position_s);
    const fwd = await player(page);
    expect(fwd.playing).toBe(false);
    expect(fwd.position_s - paused.position_s).toBeLessThanOrEqual(0.02);

    await page.getByTestId("timeline-step-back").click();
    await expect.poll(async () => (await player(page)).position_s).toBeLessThan(fwd.position_s);
    const back = await player(page);
    expect(back.playing).toBe(false);
    expect(fwd.position_s - back.position_s).toBeLessThanOrEqual(0.02);
  });

  await test.step("next event button, then a jump to the next command: lands on the event's time", async () => {
    await clickBar(page, 0);
    const from = (await player(page)).position_s;
    const nextAny = p.events.filter((e) => e.t_s > from + 0.001).sort((a, b) => a.t_s - b.t_s)[0];
    expect(nextAny, "an event after the start").toBeDefined();
    await page.getByTestId("timeline-next-event").click();
    await expect.poll(async () => (await player(page)).position_s).toBeCloseTo(nextAny!.t_s, 3);

    const at = (await player(page)).position_s;
    const nextCmd = p.events.filter((e) => e.kind === "command" && e.t_s > at + 0.001).sort((a, b) => a.t_s - b.t_s)[0];
    expect(nextCmd, "a command after the first event").toBeDefined();
    const r = await postPlayer(page, { action: "jump", kind: "command", direction: "next" });
    expect(r.ok()).toBeTruthy();
    expect(((await r.json()) as Player).position_s).toBeCloseTo(nextCmd!.t_s, 3);
    expect((await player(page)).position_s).toBeCloseTo(nextCmd!.t_s, 3);
    await expect.poll(() => shownPosition(page)).toBeCloseTo(Math.floor(nextCmd!.t_s * 10 + 1e-6) / 10, 5);
  });

  await test.step("Space plays and pauses while replaying", async () => {
    expect((await player(page)).playing).toBe(false);
    await page.evaluate(() => (document.activeElement as HTMLElement | null)?.blur());
    await page.keyboard.press("Space");
    await expect(page.getByTestId("timeline")).toHaveAttribute("data-playing", "true");
    expect((await player(page)).playing).toBe(true);
    await page.keyboard.press("Space");
    await expect(page.getByTestId("timeline")).toHaveAttribute("data-playing", "false");
    expect((await player(page)).playing).toBe(false);
  });

  await test.step("back to live: the badge and the timeline go, the world has no replay clock", async () => {
    await page.getByTestId("timeline-live").click();
    await expect(page.getByTestId("replay-badge")).toHaveCount(0);
    await expect(page.getByTestId("timeline")).toHaveCount(0);
    await expect(page.locator(".app")).not.toHaveClass(/replaying/);
    expect((await player(page)).source).toBe("live");
    await expect.poll(async () => {
      const w = await replayWorld(page);
      return { replay: w.replay, recorded: w.recorded };
    }).toEqual({ replay: null, recorded: null });
    await expect.poll(async () => (await hooks(page)).recordedDrawn).toBe(0);
  });
});

test("the page may not open a log outside the log folders", async ({ page }) => {
  const r = await postPlayer(page, { action: "open", path: "/etc/passwd" });
  expect(r.status()).toBe(422);
  expect((await player(page)).source).toBe("live");
});

// The pictures of the replay for the docs (only run with TOUCHLINE_DOCS_SHOTS=1: the config
// leaves out the "docs:" tests otherwise; 1280x720): the station
// paused at 60 % of the fixture with the timeline, its markers, the REPLAY badge and the
// recorded layer (its legend in the open layer list); then the field zoomed in with the raw
// detections on: the recorded estimate (dashed rings) beside today's over the raw detections.
test("docs: screenshots of the replay", async ({ page }) => {
  await open(page);
  await openFixture(page);
  await clickBar(page, 0.6);
  const at = await player(page);
  await expect.poll(async () => (await replayWorld(page)).replay?.epoch).toBe(at.epoch);
  await expect.poll(async () => (await hooks(page)).recordedDrawn).toBeGreaterThanOrEqual(12);
  await expect(page.getByTestId("referee-command")).toHaveText("FORCE_START");
  await page.getByTestId("layers-toggle").click();
  await expect(page.getByTestId("recorded-legend")).toBeVisible();
  await page.mouse.move(0, 0); // no hover tip on the bar
  await page.screenshot({ path: new URL("../../docs/screenshot-replay.png", import.meta.url).pathname });

  await page.getByTestId("layer-toggle-raw").check();
  await page.getByTestId("layers-toggle").click();
  // zoom on our half: six robots, the rings of the recorded estimate and the raw detections
  const p = await toScreen(page, -2000, 0);
  await page.mouse.move(p.x, p.y);
  for (let i = 0; i < 2; i++) await page.mouse.wheel(0, -240);
  await page.mouse.move(0, 0);
  await expect.poll(async () => (await hooks(page)).recordedDrawn).toBeGreaterThan(0);
  await page.screenshot({ path: new URL("../../docs/screenshot-replay-whatif.png", import.meta.url).pathname });
  // put the page's layers back (they are kept in this browser context only)
  await page.getByTestId("layers-toggle").click();
  await page.getByTestId("layer-toggle-raw").uncheck();
});
