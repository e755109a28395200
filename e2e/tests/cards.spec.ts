import { expect, test, type Page } from "@playwright/test";
import { open, ourRoles, stats, world, type Hooks } from "./helpers";

// Cards from the internal referee against the real station: a yellow card for our team (blue)
// lowers the robots it may have on the field by one; the strategy sends one robot off (role
// "substitution", SUB in the robot table) towards the halfway line by a touch line; "Clear
// cards" brings it back into play. The station is shared by every spec: the play, the cards
// and the internal referee are put back as they were found.

interface InternalReferee {
  enabled: boolean;
  command: string;
  designated_position: { x: number; y: number } | null;
  max_allowed_bots: { blue: number; yellow: number };
}

async function internal(page: Page): Promise<InternalReferee> {
  const r = await page.request.get("/api/referee");
  expect(r.ok()).toBeTruthy();
  return (await r.json()).internal as InternalReferee;
}

async function play(page: Page): Promise<string> {
  const r = await page.request.get("/api/params");
  expect(r.ok()).toBeTruthy();
  return (await r.json()).values.strategy.play as string;
}

/** Picks a play in the top bar's Play selector and waits until the station runs it. */
async function choosePlay(page: Page, name: string): Promise<void> {
  const select = page.getByTestId("play-select-bar");
  await select.selectOption(name);
  await expect(select).toHaveValue(name);
  await expect.poll(() => play(page)).toBe(name);
  await expect.poll(async () => (await world(page)).strategy?.play ?? null).toBe(name);
}

/** Our robots with role "substitution" in the world the page holds. */
const substitutes = (page: Page) =>
  page.evaluate(() =>
    (window as unknown as { __touchline: Hooks }).__touchline.roles(true).filter((r) => r.role === "substitution"));

test.describe("cards", () => {
  let original: { play: string; referee: InternalReferee } | null = null;
  let carded = false;

  test.beforeEach(async ({ page }) => {
    original = { play: await play(page), referee: await internal(page) };
    carded = false;
    // a robot under an operator's target is the operator's, not the play's: give every robot
    // back to the strategy (earlier specs may leave one behind)
    for (const r of (await world(page)).robots) {
      if (r.target?.source === "operator") await page.request.delete(`/api/robots/${r.team}/${r.id}/target`, { headers: { "X-Touchline": "1" } });
    }
    await expect.poll(async () => (await world(page)).robots.filter((r) => r.target?.source === "operator").length).toBe(0);
  });

  test.afterEach(async ({ page }) => {
    if (carded) await page.request.post("/api/referee/internal/card", { data: { team: "blue", card: "clear" } });
    if (!original) return;
    await page.request.patch("/api/params", { data: { strategy: { play: original.play } } });
    const ref = original.referee;
    const dp = ref.designated_position;
    const back = await page.request.post("/api/referee/internal/command", {
      data: dp ? { command: ref.command, designated_position: dp } : { command: ref.command },
    });
    // NORMAL_START, say, is refused out of its context: the game then goes on with FORCE_START
    const command = back.ok() ? ref.command : "FORCE_START";
    if (!back.ok()) await page.request.post("/api/referee/internal/command", { data: { command } });
    if (!ref.enabled) {
      // the station acts on the last referee message it heard: let it arrive before the
      // internal referee goes quiet (as referee.spec.ts does)
      await expect.poll(async () => (await world(page)).referee?.command).toBe(command);
      await page.request.post("/api/referee/internal/enabled", { data: { enabled: false } });
    }
  });

  test("a yellow card for blue sends one robot off as a substitution; clearing it brings it back", async ({ page }) => {
    await open(page);
    const strategy = (await world(page)).strategy;
    expect(strategy?.our_team, "the station plays blue").toBe("blue");
    await choosePlay(page, "match");

    // the internal referee lets the game run; nobody leaves yet
    await page.getByTestId("tab-referee").click();
    await page.getByTestId("ref-FORCE_START").click();
    await expect(page.getByTestId("referee-command")).toHaveText("FORCE_START");
    await expect.poll(async () => (await substitutes(page)).length).toBe(0);
    const before = (await internal(page)).max_allowed_bots.blue;
    const onField = (await world(page)).robots.filter((r) => r.team === "blue" && r.visible).length;
    expect(onField, "all of blue's robots are allowed before the card").toBeLessThanOrEqual(before);

    // yellow card for blue: one robot fewer allowed, the panel says so and warns
    const yellow = page.getByTestId("ref-card-yellow-blue");
    await expect(yellow).toHaveAccessibleName("Yellow card for blue");
    await yellow.click();
    carded = true;
    await expect(page.getByTestId("referee-error")).toHaveCount(0);
    await expect.poll(async () => (await internal(page)).max_allowed_bots.blue).toBe(before - 1);
    const robotsCell = page.getByTestId("referee-robots-blue");
    await expect(robotsCell).toHaveText(`${onField} / ${before - 1} allowed`);
    await expect(robotsCell).toHaveClass(/\bwarn\b/);
    await expect(page.getByTestId("referee-cards-blue")).toHaveText(/^1 yellow \(1[0-2]\d s\)$/);
    await expect(page.getByTestId("referee-cards-yellow")).toHaveText("none");

    // exactly one of our robots leaves, not the keeper; the others play on
    await expect.poll(async () => (await substitutes(page)).length, { timeout: 15_000 }).toBe(1);
    const [sub] = await substitutes(page);
    const roles = await ourRoles(page);
    expect(roles.filter((r) => r === "substitution"), roles.join(",")).toHaveLength(1);
    expect(roles.filter((r) => r === "goalkeeper"), roles.join(",")).toHaveLength(1);
    // the station reports the same robot leaving
    expect((await world(page)).robots.filter((r) => r.team === "blue" && r.role === "substitution").map((r) => r.id)).toEqual([sub!.id]);
    // it drives to within the rules' 1 m of where the halfway line meets a touch line
    const geo = await (await page.request.get("/api/geometry")).json() as { field_width: number };
    const halfWidth = geo.field_width / 2;
    await expect.poll(async () => {
      const r = (await world(page)).robots.find((b) => b.team === "blue" && b.id === sub!.id)!;
      return Math.round(Math.hypot(r.x, Math.abs(r.y) - halfWidth));
    }, { timeout: 20_000, message: "mm from where the halfway line meets a touch line" }).toBeLessThan(1000);
    // the field tags it (role tags are drawn) and the robot table shows SUB
    await expect.poll(async () => (await stats(page)).rolesDrawn).toBeGreaterThan(0);
    await page.getByTestId("tab-robots").click();
    const role = page.getByTestId(`robot-row-blue-${sub!.id}`).getByTestId("robot-role");
    await expect(role).toHaveText("SUB");
    await expect(role).toHaveAttribute("data-role", "substitution");
    await expect(role).toHaveAttribute("title", "Substitution");
    await expect(page.locator('[data-testid="robot-role"][data-role="substitution"]')).toHaveCount(1);

    // clear cards: all robots allowed again, nobody leaves
    await page.getByTestId("tab-referee").click();
    await page.getByTestId("ref-card-clear-blue").click();
    await expect(page.getByTestId("referee-error")).toHaveCount(0);
    await expect.poll(async () => (await internal(page)).max_allowed_bots.blue).toBe(before);
    carded = false;
    await expect(robotsCell).toHaveText(`${onField} / ${before} allowed`);
    await expect(robotsCell).not.toHaveClass(/\bwarn\b/);
    await expect(page.getByTestId("referee-cards-blue")).toHaveText("none");
    await expect.poll(async () => (await substitutes(page)).length, { timeout: 15_000 }).toBe(0);
    await expect.poll(async () => (await world(page)).robots.filter((r) => r.role === "substitution").length).toBe(0);
    await page.getByTestId("tab-robots").click();
    await expect(page.locator('[data-testid="robot-role"][data-role="substitution"]')).toHaveCount(0);
  });
});
