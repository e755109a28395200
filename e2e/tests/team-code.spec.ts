import { readFileSync, rmSync, writeFileSync } from "node:fs";
import { join } from "node:path";
import { expect, test, type Page } from "@playwright/test";
import { open, stats, world, type Hooks, type Robot, type World } from "./helpers";

// The team's own code against the real station (issue 27): the config starts the station on a
// copy of the shipped team folder (E2E_TEAM_DIR); this spec writes a play into it, picks it in
// the top bar, edits it in the Code tab and sees the robots follow; breaks it (a raise) and
// sees the error with its line, the traceback and the robots stopped and marked; fixes it and
// sees it run again; a conflict with a save on disk; a new play from the page. Every wait is
// on a condition (targets, states, the page's hooks), bounded.

const teamDir = process.env.E2E_TEAM_DIR ?? "";
const NAME = "e2e_row";
const FILE = `${NAME}.py`;
const SOURCE = `"""E2E row: our robots stand in a row at X (the Playwright spec edits X in the page)."""

from touchline import Game, Target

TITLE = "E2E row"
X = -2000.0


def play(game: Game) -> dict[int, Target]:
    orders = {}
    for k, rid in enumerate(sorted(game.mine)):
        orders[rid] = Target(X, -1500.0 + 500.0 * k, 0.0, role="row")
    return orders
`;

interface StrategyNow {
  play: string;
  our_team: "blue" | "yellow";
  our_side: "negative-x" | "positive-x";
  robot_plays: Record<string, string>;
  stopped: { id: number; play: string; reason: string }[];
}

/** The world in replay: the playhead and what the log recorded (its commands among it). */
interface ReplayNow extends World {
  replay: { position_s: number } | null;
  recorded: { commands: { team: string; id: number; forward_mps: number; left_mps: number }[] } | null;
}

async function strategy(page: Page): Promise<StrategyNow> {
  return (await world(page)).strategy as unknown as StrategyNow;
}

/** Our robots with the targets the team play gave them, as x in OUR frame (our goal at -x). */
async function teamTargetsX(page: Page): Promise<number[]> {
  const w = await world(page);
  const s = w.strategy as unknown as StrategyNow;
  const sign = s.our_side === "positive-x" ? -1 : 1;
  return w.robots
    .filter((r: Robot) => r.team === s.our_team && r.target?.source === "team")
    .map((r) => Math.round(sign * r.target!.x));
}

async function ourRobots(page: Page): Promise<{ robots: Robot[]; sign: number; team: string }> {
  const w = await world(page);
  const s = w.strategy as unknown as StrategyNow;
  return { robots: w.robots.filter((r) => r.team === s.our_team), sign: s.our_side === "positive-x" ? -1 : 1, team: s.our_team };
}

/** Puts the caret at the end of the editor line that contains `text`. */
async function caretAtEndOf(page: Page, text: string): Promise<void> {
  await page.locator(".cm-line", { hasText: text }).first().click();
  await page.keyboard.press("End");
}

/** Closes the notifications (a picture without "Play: ..." over the field). */
async function dismissToasts(page: Page): Promise<void> {
  for (let n = await page.getByTestId("toast").count(); n > 0; n--) await page.getByTestId("toast").first().getByRole("button").click();
  await expect(page.getByTestId("toast")).toHaveCount(0);
}

const save = (page: Page) => page.keyboard.press("ControlOrMeta+s");

/** "all" when each of our six robots has the play's target at x (our frame); the safety
 * envelope may move one out of a forbidden spot (near the ball at STOP, say), never by more
 * than 600 mm here. Else the xs, for the failure message. */
const all6 = (xs: number[], x: number) => (xs.length >= 6 && xs.every((v) => Math.abs(v - x) < 600) ? "all" : xs.join(","));

test.describe("team code", () => {
  let originalPlay = "match";

  test.beforeAll(() => {
    expect(teamDir, "the config gives the station a team folder of its own").not.toBe("");
  });

  test.afterAll(async ({ request }) => {
    await request.patch("/api/params", { data: { strategy: { play: originalPlay, robot_plays: {} } } });
    for (const f of [FILE, "e2e_new.py", "e2e_wall.m"]) rmSync(join(teamDir, f), { force: true });
  });

  test("edit a play in the page, save, the robots follow; break it, see the error and the stopped robots; fix it", async ({ page }) => {
    test.setTimeout(120_000);
    originalPlay = (await strategy(page).catch(() => null))?.play ?? "match";
    for (const r of (await world(page)).robots) {
      if (r.target?.source === "operator") await page.request.delete(`/api/robots/${r.team}/${r.id}/target`, { headers: { "X-Touchline": "1" } });
    }
    await open(page);

    // a new file in the folder shows up in the top bar's Team group without a reload
    writeFileSync(join(teamDir, FILE), SOURCE);
    const select = page.getByTestId("play-select-bar");
    await expect(select.locator('optgroup[label="Team"] option', { hasText: "E2E row" })).toHaveCount(1);
    await expect(select.locator('optgroup[label="Built-in"] option', { hasText: "Match" })).toHaveCount(1);
    await select.selectOption(NAME);
    await expect.poll(async () => (await strategy(page)).play, { timeout: 15_000 }).toBe(NAME);
    await expect.poll(async () => all6(await teamTargetsX(page), -2000), { timeout: 20_000 }).toBe("all");

    // the Code tab: the file runs, drives our robots; the editor shows it
    await page.getByTestId("tab-code").click();
    await page.getByTestId(`code-file-${FILE}`).click();
    await expect(page.getByTestId(`code-state-${FILE}`)).toHaveAttribute("data-state", "running");
    await expect(page.getByTestId("code-detail-robots")).toHaveText(/^\d+(, \d+){5}$/);
    await expect(page.getByTestId("code-detail-tick")).toContainText("p50");
    await expect(page.locator(".cm-content")).toContainText("X = -2000.0");

    // edit X in the page and save with Ctrl+S: the targets move, then the robots
    await caretAtEndOf(page, "X = -2000.0");
    await page.keyboard.press("Shift+Home");
    await page.keyboard.type("X = -1000.0");
    await expect(page.getByTestId("code-save-status")).toHaveAttribute("data-dirty", "true");
    await save(page);
    await expect(page.getByTestId("code-save-status")).toHaveText("saved");
    expect(readFileSync(join(teamDir, FILE), "utf8")).toContain("\nX = -1000.0\n");
    await expect.poll(async () => all6(await teamTargetsX(page), -1000), { timeout: 10_000 }).toBe("all");
    await expect
      .poll(async () => {
        const { robots, sign } = await ourRobots(page);
        return robots.filter((r) => Math.abs(sign * r.x + 1000) < 250).length;
      }, { timeout: 30_000 })
      .toBeGreaterThanOrEqual(3);

    // break it: a raise as the play's first line
    await caretAtEndOf(page, "def play(game: Game)");
    await page.keyboard.press("Enter");
    await page.keyboard.type('raise ValueError("broken on purpose")');
    await expect(page.getByTestId("code-save-status")).toHaveAttribute("data-dirty", "true");
    await save(page);
    await expect(page.getByTestId("code-save-status")).toHaveText("saved");
    const raiseLine = readFileSync(join(teamDir, FILE), "utf8").split("\n").findIndex((l) => l.includes("raise ValueError")) + 1;
    expect(raiseLine).toBeGreaterThan(0);
    await expect(page.getByTestId(`code-state-${FILE}`)).toHaveAttribute("data-state", "error");
    const error = page.getByTestId("code-error");
    await expect(error).toHaveAttribute("data-line", String(raiseLine));
    await expect(error).toContainText("broken on purpose");
    await expect(page.getByTestId("code-traceback")).toContainText(`line ${raiseLine}`);
    await expect(page.locator('.cm-line[data-error-line="true"]')).toHaveText(/raise ValueError\("broken on purpose"\)/);
    // its robots stand still and are marked: in the world, in the tab, on the field
    const { team } = await ourRobots(page);
    await expect.poll(async () => (await strategy(page)).stopped.filter((s) => s.play === NAME).length, { timeout: 10_000 }).toBeGreaterThanOrEqual(6);
    const stoppedIds = (await strategy(page)).stopped.map((s) => s.id).sort((a, b) => a - b);
    await expect(page.getByTestId(`code-stopped-${NAME}`)).toHaveAttribute("data-ids", stoppedIds.join(","));
    await expect.poll(async () => (await stats(page)).stoppedDrawn.length, { timeout: 10_000 }).toBe(stoppedIds.length);
    expect((await stats(page)).stoppedDrawn).toContain(`${team} ${stoppedIds[0]}`);
    await expect
      .poll(async () => {
        const { robots } = await ourRobots(page);
        return robots.filter((r) => stoppedIds.includes(r.id) && r.command && r.command.forward_mps === 0 && r.command.left_mps === 0).length;
      }, { timeout: 10_000 })
      .toBe(stoppedIds.length);

    // fix it: the raise line removed, saved: it runs again and nothing is marked
    await caretAtEndOf(page, "raise ValueError");
    await page.keyboard.press("Shift+Home");
    await page.keyboard.press("Shift+Home");
    await page.keyboard.press("Backspace");
    await page.keyboard.press("Backspace");
    await expect(page.getByTestId("code-save-status")).toHaveAttribute("data-dirty", "true");
    await save(page);
    await expect(page.getByTestId("code-save-status")).toHaveText("saved");
    expect(readFileSync(join(teamDir, FILE), "utf8")).toBe(SOURCE.replace("X = -2000.0", "X = -1000.0"));
    await expect(page.getByTestId(`code-state-${FILE}`)).toHaveAttribute("data-state", "running");
    await expect(page.getByTestId("code-error")).toHaveCount(0);
    await expect(page.getByTestId("code-stopped")).toHaveCount(0);
    await expect.poll(async () => (await strategy(page)).stopped.length, { timeout: 10_000 }).toBe(0);
    await expect.poll(async () => (await stats(page)).stoppedDrawn.length).toBe(0);
    await expect.poll(async () => all6(await teamTargetsX(page), -1000), { timeout: 10_000 }).toBe("all");
  });

  test("a save on disk meanwhile is a conflict: the edits stay until reloaded from disk", async ({ page }) => {
    writeFileSync(join(teamDir, FILE), SOURCE.replace("X = -2000.0", "X = -1000.0"));
    await open(page);
    await page.getByTestId("tab-code").click();
    await page.getByTestId(`code-file-${FILE}`).click();
    await expect(page.locator(".cm-content")).toContainText("X = -1000.0");
    await caretAtEndOf(page, "X = -1000.0");
    await page.keyboard.type("  # mine");
    // another editor saves the file
    const theirs = SOURCE.replace("X = -2000.0", "X = -500.0");
    writeFileSync(join(teamDir, FILE), theirs);
    await page.getByTestId("code-save").click();
    await expect(page.getByTestId("code-conflict")).toContainText("changed on disk");
    expect(readFileSync(join(teamDir, FILE), "utf8")).toBe(theirs);
    await expect(page.locator(".cm-content")).toContainText("X = -1000.0  # mine");
    await page.getByTestId("code-conflict-reload").click();
    await expect(page.getByTestId("code-conflict")).toHaveCount(0);
    await expect(page.locator(".cm-content")).toContainText("X = -500.0");
    await expect(page.getByTestId("code-save-status")).toHaveAttribute("data-dirty", "false");
  });

  test("new plays from the page (Python, Octave); an Octave play given to one robot drives it", async ({ page }) => {
    test.setTimeout(90_000);
    await open(page);
    await page.getByTestId("tab-code").click();
    await page.getByTestId("code-new").click();
    await page.getByTestId("code-new-name").fill("e2e new");
    await page.getByTestId("code-new-create").click();
    await expect(page.getByTestId("code-file-e2e_new.py")).toHaveAttribute("aria-current", "true");
    await expect(page.getByTestId("code-group-play").getByTestId("code-file-e2e_new.py")).toHaveCount(1);
    await expect(page.locator(".cm-content")).toContainText("def play(game: Game)");
    await expect(page.getByTestId("play-select-bar").locator('optgroup[label="Team"] option', { hasText: "E2e new" })).toHaveCount(1);

    // an Octave play: the paper's style, highlighted as Octave, listed as a play
    await page.getByTestId("code-new").click();
    await page.getByTestId("code-new-name").fill("e2e_wall");
    await page.getByTestId("code-new-language").selectOption("octave");
    await page.getByTestId("code-new-create").click();
    await expect(page.getByTestId("code-group-play").getByTestId("code-file-e2e_wall.m")).toHaveCount(1);
    await expect(page.locator(".cm-content")).toContainText("function orders = e2e_wall(ours, theirs, ball, game)");
    await expect(page.locator(".cm-content")).toHaveAttribute("data-language", "octave");

    // given to one robot of ours in its panel (the rest keep the team's play)
    const { team, robots } = await ourRobots(page);
    const rid = robots.map((r) => r.id).sort((a, b) => a - b)[1]!;
    await page.getByTestId("tab-robots").click();
    await page.getByTestId(`robot-row-${team}-${rid}`).click();
    const choice = page.getByTestId("robot-play-select");
    await expect(choice.locator('optgroup[label="Team"] option', { hasText: "E2e wall" })).toHaveCount(1);
    await choice.selectOption("e2e_wall");
    await expect.poll(async () => (await strategy(page)).robot_plays[String(rid)], { timeout: 15_000 }).toBe("e2e_wall");
    // the template's row: x = -2000 in our frame (the Octave worker may take a moment to start)
    await expect
      .poll(async () => {
        const { robots: rs, sign } = await ourRobots(page);
        const r = rs.find((x) => x.id === rid)!;
        return r.target?.source === "team" ? Math.round(sign * r.target.x) : null;
      }, { timeout: 30_000 })
      .toBe(-2000);
    await expect(page.getByTestId("robot-play-effective")).toHaveAttribute("data-value", "e2e_wall");
    await expect(page.getByTestId("robot-play-effective")).toHaveAttribute("data-override", "true");
    // back to the team's play
    await choice.selectOption("");
    await expect.poll(async () => (await strategy(page)).robot_plays[String(rid)], { timeout: 15_000 }).not.toBe("e2e_wall");
  });

  test("a team processor's outputs: shown in the Code tab, plotted from there, among the Plots tab's signals", async ({ page }) => {
    await open(page);
    await page.getByTestId("tab-code").click();
    // the shipped ball-possession processor (team/possession.py) runs from the start
    await page.getByTestId("code-file-possession.py").click();
    await expect(page.getByTestId("code-state-possession.py")).toHaveAttribute("data-state", "running");
    await expect(page.getByTestId("code-detail-outputs")).toContainText("ours");
    await page.getByTestId("code-plot-ours").click();
    await expect(page.getByTestId("tab-plots")).toHaveAttribute("aria-selected", "true");
    const plotted = () =>
      page.evaluate(() => {
        const api = (window as unknown as { __touchline: Hooks }).__touchline;
        const p = api.plots().find((x) => x.keys.includes("team.possession.ours"));
        return { points: p?.points ?? 0, signal: api.signals().includes("team.possession.ours") };
      });
    await expect.poll(async () => (await plotted()).points, { timeout: 10_000 }).toBeGreaterThan(2);
    expect((await plotted()).signal).toBe(true);
    // found by the signal search as well
    await page.getByTestId("add-plot").click();
    await page.getByTestId("signal-search").fill("team possession");
    await expect(page.getByTestId("signal-team.possession.ours")).toBeVisible();
    await page.keyboard.press("Escape");
    for (let n = await page.getByRole("button", { name: "Remove plot" }).count(); n > 0; n--)
      await page.getByRole("button", { name: "Remove plot" }).last().click();
  });

  test("what-if on a recorded log: the team play runs on the replay, its targets and commands drawn beside the recording and the commands it sent", async ({ page }) => {
    test.setTimeout(90_000);
    writeFileSync(join(teamDir, FILE), SOURCE);
    await open(page);
    try {
      await page.getByTestId("open-log").click();
      await page.getByTestId("log-open-fieldsim-2s.log.gz").click();
      await expect(page.getByTestId("replay-badge")).toBeVisible();
      await expect.poll(async () => ((await (await page.request.get("/api/player")).json()) as { loading: number | null }).loading).toBeNull();
      await page.getByTestId("play-select-bar").selectOption(NAME);
      await expect.poll(async () => (await strategy(page)).play, { timeout: 15_000 }).toBe(NAME);
      // play the 2.5 s log at half speed: the strategy runs on each replayed world
      await page.request.post("/api/player", { data: { action: "play", speed: 0.5 }, headers: { "Content-Type": "application/json" } });
      await expect.poll(async () => all6(await teamTargetsX(page), -2000), { timeout: 15_000 }).toBe("all");
      // drawn: the play's commands (arrows) beside the log's own estimate (rings); nothing sent
      await expect.poll(async () => (await stats(page)).commandsDrawn, { timeout: 10_000 }).toBeGreaterThan(0);
      expect((await stats(page)).recordedDrawn).toBeGreaterThan(0);
      const w = await world(page);
      expect((w as unknown as { replay: unknown }).replay).not.toBeNull();

      // paused where the log's robot 1 was driving (2.2 s): what the play commands each robot
      // now beside the command the log sent it then, for the same robots, both drawn
      const post = (data: object) => page.request.post("/api/player", { data, headers: { "Content-Type": "application/json" } });
      await post({ action: "pause" });
      await post({ action: "seek", position_s: 2.2 });
      const compared = async () => {
        const now = (await world(page)) as ReplayNow;
        if (Math.abs((now.replay?.position_s ?? 0) - 2.2) > 1e-6 || !now.recorded) return "not at 2.2 s";
        const sentThen = now.recorded.commands.filter((c) => Math.hypot(c.forward_mps, c.left_mps) > 0.05);
        const both = sentThen.filter((c) => {
          const r = now.robots.find((x) => x.team === c.team && x.id === c.id);
          return r?.target?.source === "team" && r.command && Math.hypot(r.command.forward_mps, r.command.left_mps) > 0.05;
        });
        return both.length > 0 ? "both" : `sent then ${sentThen.length}, with the play's own command 0`;
      };
      await expect.poll(compared, { timeout: 15_000 }).toBe("both");
      await expect.poll(async () => (await stats(page)).recordedCommandsDrawn, { timeout: 10_000 }).toBeGreaterThan(0);
      expect((await stats(page)).commandsDrawn).toBeGreaterThan(0);
      // the layers panel says which arrow is which
      await page.getByTestId("layers-toggle").click();
      await expect(page.getByTestId("commands-legend")).toContainText("commanded now");
      await expect(page.getByTestId("commands-legend")).toContainText("sent then (log)");
      await page.getByTestId("layers-toggle").click();
    } finally {
      await page.request.post("/api/player", { data: { action: "live" }, headers: { "Content-Type": "application/json" } });
    }
  });

  // The pictures of docs/team-code.md's walkthrough (docs/img/team-code-*.png; only with
  // TOUCHLINE_DOCS_SHOTS=1: `npm run docs:shots`; 1400x900). The config's station runs on a
  // copy of the shipped team folder (step 1) given with --team-dir (step 2, `make run
  // TEAM=...`): the folder in the Code tab; the pass drill passing; an edit of its SPOTS in
  // the page; saved: reloaded, the robots at the new spots; a typo: the error, its line, the
  // traceback, the robots stopped and ringed. The file is put back at the end.
  test("docs: the team-code walkthrough", async ({ page }) => {
    test.setTimeout(180_000);
    const file = join(teamDir, "pass_drill.py");
    const original = readFileSync(file, "utf8");
    const shot = async (name: string) => {
      await dismissToasts(page);
      await page.mouse.move(0, 0);
      await page.screenshot({ path: new URL(`../../docs/img/${name}.png`, import.meta.url).pathname });
    };
    const ticks = page.getByTestId("code-detail-ticks");
    await page.setViewportSize({ width: 1400, height: 900 });
    await open(page);
    // the first visit's name question answered (it sits at the top of every tab)
    if (await page.getByTestId("name-prompt").isVisible()) await page.getByTestId("name-save").click();
    try {
      // 1. the copied folder as the station sees it: plays, a processor, what each says
      await page.getByTestId("tab-code").click();
      await page.getByTestId("code-file-pass_drill.py").click();
      await expect(page.locator(".cm-content")).toContainText("Try changing");
      await expect(page.getByTestId("code-group-play").getByTestId("code-file-keeper_wall.m")).toHaveCount(1);
      await expect(page.getByTestId("code-group-processor").getByTestId("code-file-possession.py")).toHaveCount(1);
      await shot("team-code-1-folder");

      // 2. its play chosen in the top bar: the two passers pass, the others wait in a row
      await page.getByTestId("tab-robots").click();
      await page.getByTestId("play-select-bar").selectOption("pass_drill");
      await expect.poll(async () => (await strategy(page)).play, { timeout: 15_000 }).toBe("pass_drill");
      // a pass from one spot to the other under way (the field draws the kick's line)
      const passFrom = (spots: [number, number][]) => async () => {
        const w = await world(page);
        const s = w.strategy as unknown as StrategyNow;
        const sign = s.our_side === "positive-x" ? -1 : 1;
        const kick = (w.ball as unknown as { kick?: { robot: { team: string } | null; start_x: number; start_y: number } | null } | null)?.kick;
        return kick?.robot?.team === s.our_team && spots.some(([x, y]) => Math.hypot(sign * kick.start_x - x, sign * kick.start_y - y) < 300);
      };
      await expect.poll(passFrom([[-2000, -1500], [-2000, 1500]]), { timeout: 60_000, intervals: [50] }).toBe(true);
      await shot("team-code-2-running");

      // 3. an edit in the page (an editor of your own does the same): new spots for the two
      await page.getByTestId("tab-code").click();
      await page.getByTestId("code-file-pass_drill.py").click();
      await expect(ticks).toContainText("0 errors");
      await caretAtEndOf(page, "SPOTS = (");
      await page.keyboard.press("Shift+Home");
      await page.keyboard.type("SPOTS = ((-2500.0, -1000.0), (-1000.0, 1500.0))");
      await expect(page.getByTestId("code-save-status")).toHaveAttribute("data-dirty", "true");
      await shot("team-code-3-edit");

      // 4. saved (Ctrl+S): reloaded in place, the robots go to the new spots
      await save(page);
      await expect(page.getByTestId("code-save-status")).toHaveText("saved");
      expect(readFileSync(file, "utf8")).toContain("SPOTS = ((-2500.0, -1000.0), (-1000.0, 1500.0))");
      await expect(page.getByTestId("code-detail-reloaded")).toContainText("2×");
      const atSpots = async () => {
        const { robots, sign } = await ourRobots(page);
        const near = (x: number, y: number) => robots.some((r) => Math.hypot(sign * r.x - x, sign * r.y - y) < 300);
        return near(-2500, -1000) && near(-1000, 1500);
      };
      await expect.poll(atSpots, { timeout: 60_000 }).toBe(true);
      await expect.poll(passFrom([[-2500, -1000], [-1000, 1500]]), { timeout: 60_000, intervals: [50] }).toBe(true);
      await expect(ticks).toContainText("0 errors");
      await shot("team-code-4-reloaded");

      // 5. a typo, saved: the error with its line and traceback, the play's robots stopped
      // (to the end of the file, where play() is: the editor draws only the lines in view)
      await page.keyboard.press("ControlOrMeta+End");
      await caretAtEndOf(page, "mine = sorted(game.mine)");
      await page.keyboard.press("Shift+Home");
      await page.keyboard.type("mine = sorted(game.mien)");
      await save(page);
      await expect(page.getByTestId("code-error")).toContainText("mien");
      await expect(page.locator('.cm-line[data-error-line="true"]')).toHaveCount(1);
      await expect(page.getByTestId("code-traceback")).toContainText("pass_drill.py");
      await expect.poll(async () => (await stats(page)).stoppedDrawn.length, { timeout: 10_000 }).toBeGreaterThanOrEqual(6);
      await expect(ticks).toContainText(" 1 error");
      await shot("team-code-5-error");
      // one typo, one error (counted once, however long it stays)
      await expect(ticks).toContainText(" 1 error");
    } finally {
      writeFileSync(file, original);
    }
    await expect(page.getByTestId("code-state-pass_drill.py")).toHaveAttribute("data-state", "running");
  });
});
