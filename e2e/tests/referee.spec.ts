import { expect, test, type Page } from "@playwright/test";
import { clickField, open, stats, world, type Hooks } from "./helpers";

// The ball placement mark on the field against the real station and its internal referee.
// The official game controller sends its designated position during every command, not only
// during a ball placement ((0,0) at the start, the old mark during STOP and timeouts); the
// internal referee sends it during a placement only. So the page's websocket is routed and the
// last placement position is put back into every later referee state, as the game controller
// would send it: the page must still draw no mark during STOP.

/** Routes the page's websocket: the station's messages, with the last mark kept like the GC does. */
async function keepLastMarkLikeTheGameController(page: Page): Promise<{ rewritten: () => number }> {
  let mark: { x: number; y: number } | null = null;
  let rewritten = 0;
  await page.routeWebSocket("**/api/ws", (ws) => {
    const server = ws.connectToServer();
    ws.onMessage((m) => server.send(m));
    server.onMessage((m) => {
      if (typeof m !== "string") {
        ws.send(m);
        return;
      }
      const msg = JSON.parse(m) as { type: string; world?: { referee?: { designated_position?: { x: number; y: number } | null } | null } };
      const ref = msg.type === "world" || msg.type === "snapshot" ? msg.world?.referee : null;
      if (ref?.designated_position) mark = ref.designated_position;
      else if (ref && mark) {
        ref.designated_position = mark;
        rewritten++;
      }
      ws.send(JSON.stringify(msg));
    });
  });
  return { rewritten: () => rewritten };
}

const hooks = (page: Page) => page.evaluate(() => {
  const h = (window as unknown as { __touchline: Hooks }).__touchline;
  return { drawn: h.stats().designatedDrawn, draws: h.stats().fieldDraws, world: h.getWorld()?.referee ?? null };
});

test("the ball placement mark shows during BALL_PLACEMENT, not during STOP though the referee still sends it", async ({ page }) => {
  const route = await keepLastMarkLikeTheGameController(page);
  await open(page);
  await page.getByTestId("tab-referee").click();
  const spot = { x: 1500, y: -1000 };
  try {
    await page.getByTestId("ref-STOP").click();
    await expect(page.getByTestId("referee-command")).toHaveText("STOP");
    await expect.poll(async () => (await hooks(page)).draws).toBeGreaterThan(0);
    expect((await stats(page)).designatedDrawn).toBeNull();

    // ball placement for blue at a clicked point: the mark is drawn there
    await page.getByTestId("ref-BALL_PLACEMENT_BLUE").click();
    await expect(page.getByTestId("placement-hint")).toBeVisible();
    await clickField(page, [spot], 0); // robots do not matter while placing; a toast would
    await expect(page.getByTestId("referee-command")).toHaveText("BALL_PLACEMENT_BLUE");
    const dp = (await world(page)).referee?.designated_position;
    expect(dp, "the station's referee carries the clicked position").toBeTruthy();
    expect(Math.hypot(dp!.x - spot.x, dp!.y - spot.y)).toBeLessThan(40);
    await expect.poll(async () => (await stats(page)).designatedDrawn).toEqual(dp);
    await expect(page.getByTestId("referee-placement")).toHaveText(`${Math.round(dp!.x)}, ${Math.round(dp!.y)} mm`);

    // STOP: the referee state the page gets still carries the mark; none is drawn
    await page.getByTestId("ref-STOP").click();
    await expect(page.getByTestId("referee-command")).toHaveText("STOP");
    await expect.poll(async () => (await hooks(page)).world?.designated_position ?? null).toEqual(dp);
    expect(route.rewritten()).toBeGreaterThan(0);
    await expect.poll(async () => (await stats(page)).designatedDrawn).toBeNull();
    // and it stays so on the frames that follow (the world streams at up to 60 Hz)
    const d0 = (await hooks(page)).draws;
    await expect.poll(async () => (await hooks(page)).draws).toBeGreaterThan(d0 + 10);
    const after = await hooks(page);
    expect(after.world?.command).toBe("STOP");
    expect(after.world?.designated_position).toEqual(dp);
    expect(after.drawn).toBeNull();
    await expect(page.getByTestId("referee-placement")).toHaveText("—");
  } finally {
    await page.request.post("/api/referee/internal/command", { data: { command: "FORCE_START" } });
    // the station keeps acting on the last referee message it heard: let FORCE_START arrive
    // before the internal referee goes quiet
    await expect.poll(async () => (await world(page)).referee?.command).toBe("FORCE_START");
    await page.request.post("/api/referee/internal/enabled", { data: { enabled: false } });
  }
});
