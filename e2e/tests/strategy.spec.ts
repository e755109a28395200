import { expect, test, type Page } from "@playwright/test";
import { open, ourRoles, stats, world, type Hooks, type Robot, type World } from "./helpers";

// Strategy against the real station: plays chosen with the Play selector change our robots'
// roles (read back from /api/world and from the page's world), the paths layer, the situation
// banner and the Engine panel. The station is shared by every spec: each test puts back the
// play and the engine it found.

async function params(page: Page): Promise<{ strategy: { play: string; engine: string } }> {
  const r = await page.request.get("/api/params");
  expect(r.ok()).toBeTruthy();
  return (await r.json()).values;
}

function ours(w: World): Robot[] {
  const team = w.strategy?.our_team;
  expect(team, "the world reports the strategy's team").toBeTruthy();
  return w.robots.filter((r) => r.team === team);
}

/** Roles of our robots in /api/world, sorted (for readable failures). */
async function roles(page: Page): Promise<string[]> {
  return ours(await world(page)).map((r) => r.role ?? "none").sort();
}

/** Picks a play in the top bar's Play selector and waits until the station runs it. */
async function choosePlay(page: Page, name: string): Promise<void> {
  const select = page.getByTestId("play-select-bar");
  await select.selectOption(name);
  await expect(select).toHaveValue(name);
  await expect.poll(async () => (await params(page)).strategy.play).toBe(name);
  await expect.poll(async () => (await world(page)).strategy?.play ?? null).toBe(name);
}

test.describe("strategy", () => {
  let original: { play: string; engine: string } | null = null;

  test.beforeEach(async ({ page }) => {
    const p = await params(page);
    original = { play: p.strategy.play, engine: p.strategy.engine };
    // A robot under an operator's target is the operator's, not the play's (role "operator"):
    // earlier specs may leave one behind, so give every robot back to the strategy.
    for (const r of (await world(page)).robots) {
      if (r.target?.source === "operator") await page.request.delete(`/api/robots/${r.team}/${r.id}/target`, { headers: { "X-Touchline": "1" } });
    }
    await expect.poll(async () => (await world(page)).robots.filter((r) => r.target?.source === "operator").length).toBe(0);
  });

  test.afterEach(async ({ page }) => {
    if (original) await page.request.patch("/api/params", { data: { strategy: original } });
  });

  test("the Play selector in the top bar switches plays; roles follow in the world", async ({ page }) => {
    await open(page);
    const select = page.getByTestId("play-select-bar");
    // found by its label, listed with titles, the current play selected, described on hover
    await expect(page.getByRole("combobox", { name: "Play" }).first()).toHaveAttribute("data-testid", "play-select-bar");
    const info = await (await page.request.get("/api/strategy")).json() as { play: string; plays: { name: string; title: string; description: string }[] };
    expect(info.plays.map((p) => p.name)).toEqual(expect.arrayContaining(["match", "defend", "formation"]));
    await expect(select.locator("option")).toHaveText(info.plays.map((p) => p.title));
    await expect(select).toHaveValue(info.play);

    await choosePlay(page, "defend");
    const defend = info.plays.find((p) => p.name === "defend")!;
    await expect(select).toHaveAttribute("title", defend.description || defend.title);
    await expect.poll(() => roles(page), { timeout: 15_000 }).not.toContain("attacker");
    await expect.poll(() => roles(page), { timeout: 15_000 }).toEqual(expect.arrayContaining(["defender", "goalkeeper"]));
    let r = await roles(page);
    expect(r).not.toContain("attacker");
    // the page holds the same world: its hooks and the role tags on the field agree
    await expect.poll(async () => (await ourRoles(page)).includes("defender")).toBe(true);
    await expect.poll(async () => (await stats(page)).rolesDrawn).toBeGreaterThan(0);

    await choosePlay(page, "formation");
    await expect.poll(async () => {
      const rs = await roles(page);
      return rs.length > 0 && rs.every((x) => x === "formation") ? "all formation" : rs.join(",");
    }, { timeout: 15_000 }).toBe("all formation");

    await choosePlay(page, "match");
    await expect.poll(async () => {
      const rs = await roles(page);
      return rs.filter((x) => x === "goalkeeper").length === 1 && rs.includes("attacker") ? "one keeper, attackers" : rs.join(",");
    }, { timeout: 15_000 }).toBe("one keeper, attackers");
    r = await roles(page);
    expect(r.filter((x) => x === "goalkeeper")).toHaveLength(1);

    // the situation banner near the field shows what the strategy makes of the game
    const banner = page.getByTestId("situation-banner");
    await expect(banner).toBeVisible();
    await expect(page.getByTestId("situation-side")).toContainText("we defend");
    await expect.poll(async () => {
      const text = (await page.getByTestId("situation-text").innerText()).trim();
      const s = (await world(page)).strategy!;
      return text === (s.situation_text || s.situation);
    }).toBe(true);
  });

  test("keyboard: the Play selector is reachable and changes the play with the arrow keys", async ({ page }) => {
    await open(page);
    const select = page.getByTestId("play-select-bar");
    // the plays come with the station's parameters: wait for them, not for the first render
    await expect.poll(() => select.locator("option").count()).toBeGreaterThan(1);
    const names = await select.locator("option").evaluateAll((os) => os.map((o) => (o as HTMLOptionElement).value));
    await choosePlay(page, names[0]!);
    await select.focus();
    await expect(select).toBeFocused();
    await page.keyboard.press("ArrowDown");
    await expect(select).toHaveValue(names[1]!);
    await expect.poll(async () => (await params(page)).strategy.play).toBe(names[1]);
  });

  test("Robots tab: the play with its description; the selected robot's role", async ({ page }) => {
    await open(page);
    await page.getByTestId("tab-robots").click();
    const panel = page.getByTestId("play-select-panel");
    await expect(panel).toHaveAttribute("aria-label", "Play");
    await panel.selectOption("match");
    await expect(page.getByTestId("play-select-bar")).toHaveValue("match"); // one parameter, both selectors
    await expect.poll(async () => (await params(page)).strategy.play).toBe("match");
    const info = await (await page.request.get("/api/strategy")).json() as { plays: { name: string; description: string }[] };
    await expect(page.getByTestId("play-description")).toHaveText(info.plays.find((p) => p.name === "match")!.description);

    // Without a referee keeper id the goalkeeper slot goes by cost: it can move to another
    // robot between reading the world and the click. Select the keeper as it is now, again if
    // it moved meanwhile; the panel must show the selected robot's role.
    await expect(async () => {
      const keeper: Robot | undefined = ours(await world(page)).find((r) => r.role === "goalkeeper");
      expect(keeper).toBeDefined();
      const row = page.getByTestId(`robot-row-${keeper!.team}-${keeper!.id}`);
      await row.click();
      await expect(page.getByTestId("robot-role-detail")).toHaveText("Goalkeeper (GK)", { timeout: 2_000 });
      await expect(row.getByTestId("robot-role")).toHaveText("GK", { timeout: 1_000 });
    }).toPass({ timeout: 20_000 });
  });

  test("the paths layer toggle hides and shows the planned paths", async ({ page }) => {
    await open(page);
    await choosePlay(page, "match");
    // some robot of ours plans a path, and the field draws it (paths are on by default)
    await expect.poll(async () => ours(await world(page)).filter((r) => (r.path?.length ?? 0) > 0).length, { timeout: 15_000 })
      .toBeGreaterThan(0);
    await expect.poll(async () => (await stats(page)).pathsDrawn).toBeGreaterThan(0);

    await page.getByTestId("layers-toggle").click();
    const toggle = page.getByTestId("layer-toggle-paths");
    await expect(toggle).toBeChecked();
    await toggle.click();
    await expect(toggle).not.toBeChecked();
    await expect.poll(async () => (await stats(page)).pathsDrawn).toBe(0);
    // the paths are still in the page's world: only the drawing is off
    const withPath = await page.evaluate(() =>
      (window as unknown as { __touchline: Hooks }).__touchline.paths().filter((p) => (p.path?.length ?? 0) > 0).length);
    expect(withPath).toBeGreaterThan(0);
    // still drawing frames with paths off (not a frozen canvas)
    const draws = (await stats(page)).fieldDraws;
    await expect.poll(async () => (await stats(page)).fieldDraws).toBeGreaterThan(draws);
    expect((await stats(page)).pathsDrawn).toBe(0);

    await toggle.click();
    await expect(toggle).toBeChecked();
    await expect.poll(async () => (await stats(page)).pathsDrawn).toBeGreaterThan(0);
  });

  test("Health tab: the Engine panel, off and with the numpy engine", async ({ page }) => {
    await open(page);
    await choosePlay(page, "match");
    await page.getByTestId("tab-health").click();
    const panel = page.getByTestId("engine-panel");
    await expect(panel).toBeVisible();

    // engine off, chosen on the Params tab (an enum: a select)
    await page.getByTestId("tab-params").click();
    await page.getByTestId("params-filter").fill("engine");
    const engineSelect = page.getByTestId("param-input-strategy.engine");
    await expect(engineSelect).toHaveJSProperty("tagName", "SELECT");
    await engineSelect.selectOption("off");
    await expect.poll(async () => (await params(page)).strategy.engine).toBe("off");
    await page.getByTestId("tab-health").click();
    await expect(panel).toHaveAttribute("data-engine", "off");
    await expect(page.getByTestId("engine-off")).toContainText("engine off");

    // the numpy engine: its kind, function and growing call count show up
    await page.getByTestId("tab-params").click();
    await page.getByTestId("params-filter").fill("engine");
    await page.getByTestId("param-input-strategy.engine").selectOption("numpy");
    await expect.poll(async () => (await params(page)).strategy.engine).toBe("numpy");
    await page.getByTestId("tab-health").click();
    await expect(panel).toHaveAttribute("data-engine", "numpy", { timeout: 30_000 });
    await expect(page.getByTestId("engine-kind")).toHaveText("numpy");
    await expect(page.getByTestId("engine-function")).not.toHaveText("");
    const calls = async () => Number((await page.getByTestId("engine-calls").innerText()).split("/")[0]!.trim());
    await expect.poll(calls, { timeout: 30_000 }).toBeGreaterThan(0);
    const first = await calls();
    await expect.poll(calls, { timeout: 10_000 }).toBeGreaterThan(first);
    // the text fields of the group are text inputs
    await page.getByTestId("tab-params").click();
    await page.getByTestId("params-filter").fill("goalkeeper_function");
    await expect(page.getByTestId("param-input-strategy.goalkeeper_function")).toHaveAttribute("inputmode", "text");
  });

  test("the Play selector stays usable at 390 px", async ({ page }) => {
    await page.setViewportSize({ width: 390, height: 844 });
    await open(page);
    const select = page.getByTestId("play-select-bar");
    await expect(select).toBeVisible();
    const box = (await select.boundingBox())!;
    expect(box.x).toBeGreaterThanOrEqual(0);
    expect(box.x + box.width).toBeLessThanOrEqual(390);
    expect(box.height).toBeGreaterThanOrEqual(30); // a finger-sized target
    await choosePlay(page, "defend");
    await expect.poll(() => roles(page), { timeout: 15_000 }).not.toContain("attacker");
  });
});
