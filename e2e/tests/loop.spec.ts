import { expect, test, type Page } from "@playwright/test";
import { clickField, world, type World } from "./helpers";

async function waitForRobots(page: Page, n: number): Promise<World> {
  let w: World = { robots: [], ball: null, estop: false, referee: null };
  await expect
    .poll(async () => {
      w = await world(page);
      return w.robots.filter((r) => r.visible).length;
    }, { timeout: 30_000 })
    .toBeGreaterThanOrEqual(n);
  return w;
}

test("the page shows the robots that /api/world reports", async ({ page }) => {
  await page.goto("/");
  await expect(page.getByTestId("connection-status")).toContainText("connected");
  const w = await waitForRobots(page, 12);
  const blue = w.robots.filter((r) => r.team === "blue");
  const yellow = w.robots.filter((r) => r.team === "yellow");
  expect(blue.length).toBe(6);
  expect(yellow.length).toBe(6);
  for (const r of w.robots) {
    await expect(page.getByTestId(`robot-row-${r.team}-${r.id}`)).toBeVisible();
  }
  // the yellow robots stand still: the table shows their positions as the API does
  for (const r of yellow) {
    const row = page.getByTestId(`robot-row-${r.team}-${r.id}`);
    const x = Number(await row.getByTestId("robot-x").innerText());
    const y = Number(await row.getByTestId("robot-y").innerText());
    expect(Math.abs(x - r.x)).toBeLessThan(60);
    expect(Math.abs(y - r.y)).toBeLessThan(60);
  }
  await expect(page.getByTestId("vision-rate")).not.toHaveText(/^0/);
  const shot = await page.getByTestId("field-canvas").screenshot();
  expect(shot.byteLength).toBeGreaterThan(5000);
});

test("click a robot, click a point: the robot drives there", async ({ page }) => {
  await page.goto("/");
  await expect(page.getByTestId("connection-status")).toContainText("connected");
  const w = await waitForRobots(page, 12);
  const robot = w.robots.find((r) => r.team === "blue" && r.id === 2)!;
  const canvas = page.getByTestId("field-canvas");
  const box = (await canvas.boundingBox())!;
  const toScreen = async (x: number, y: number) =>
    page.evaluate(([xx, yy]) => (window as unknown as {
      __touchline: { worldToScreen(x: number, y: number): { x: number; y: number } };
    }).__touchline.worldToScreen(xx, yy), [x, y]);

  // the robot moves under the demo: read its position right before the click
  const now = (await world(page)).robots.find((r) => r.team === "blue" && r.id === 2)!;
  const p = await toScreen(now.x, now.y);
  await page.mouse.click(box.x + p.x, box.y + p.y);
  await expect(page.getByTestId("selected-robot")).toContainText("blue 2");

  // on the opponent half, away from everyone's formation; a spot no robot and no toast covers
  const target = await clickField(page, [{ x: 1500, y: 1200 }, { x: 2000, y: -1200 }, { x: 1000, y: 2200 }]);
  await expect(page.getByTestId("selected-robot")).toContainText("blue 2");

  await expect
    .poll(async () => {
      const r = (await world(page)).robots.find((rr) => rr.team === "blue" && rr.id === 2)!;
      return Math.hypot(r.x - target.x, r.y - target.y);
    }, { timeout: 30_000, intervals: [250] })
    .toBeLessThan(150);
  expect(Math.hypot(robot.x - target.x, robot.y - target.y)).toBeGreaterThan(1000);
});

test("the top bar's buttons stay whole and apart at laptop widths", async ({ page }) => {
  // at 1441-1700 px "new file" broke in two and was drawn over the Logs button
  await page.goto("/");
  await expect(page.getByTestId("record-new-file")).toBeVisible();
  for (const width of [1920, 1600, 1450, 1280]) {
    await page.setViewportSize({ width, height: 800 });
    const buttons = [
      page.getByTestId("record-new-file"),
      page.getByRole("button", { name: "Logs", exact: true }),
    ];
    const boxes = [];
    for (const b of buttons) {
      await expect(b).toBeVisible();
      const box = (await b.boundingBox())!;
      expect(box.height, `${width} px: one line`).toBeLessThan(40);
      boxes.push(box);
    }
    const [nf, logs] = boxes;
    expect(nf.x + nf.width, `${width} px: "new file" ends before Logs starts`).toBeLessThanOrEqual(logs.x);
  }
});

test("the top bar's play select shows the whole name of every built-in play at laptop widths", async ({ page }) => {
  // at 1280 px "Formation (classroom)" was cut to "Formation (cl"
  await page.goto("/");
  const select = page.getByTestId("play-bar").locator("select");
  await expect(select).toBeVisible();
  await expect.poll(async () => select.locator("option").count()).toBeGreaterThan(3);
  for (const width of [1920, 1600, 1450, 1280]) {
    await page.setViewportSize({ width, height: 800 });
    const fit = await select.evaluate((el: HTMLSelectElement) => {
      const cs = getComputedStyle(el);
      const ctx = document.createElement("canvas").getContext("2d")!;
      ctx.font = `${cs.fontWeight} ${cs.fontSize} ${cs.fontFamily}`;
      // the built-in plays (a team's titles are the team's to keep short)
      const names = Array.from(el.querySelectorAll<HTMLOptionElement>("[data-testid=play-group-builtin] option"), (o) => o.text);
      const widest = Math.max(...names.map((t) => ctx.measureText(t).width));
      // the text's room: the box without its padding and the drop-down arrow (about 20 px)
      const room = el.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight) - 20;
      return { names, widest, room };
    });
    expect(fit.names.length, `${width} px: the built-in plays listed`).toBeGreaterThan(3);
    expect(fit.widest, `${width} px: ${JSON.stringify(fit)}`).toBeLessThanOrEqual(fit.room);
  }
});
