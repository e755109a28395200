// Helpers shared by the end-to-end specs: the world as /api/world reports it, opening the
// page once the station streams, and the page's test hooks (window.__touchline).
import { expect, type Page } from "@playwright/test";

export interface Control { algorithm: string; phase: string; c_estimate: number }
export interface Robot {
  team: string; id: number; x: number; y: number; vx: number; vy: number; visible: boolean;
  filter?: string; control?: Control | null;
  target: { x: number; y: number; orientation: number | null; source: string } | null;
}
export interface World {
  robots: Robot[]; ball: { x: number; y: number } | null; estop: boolean;
  referee: { source: string; command: string } | null;
}

export interface Hooks {
  worldToScreen(x: number, y: number): { x: number; y: number };
  plots(): { id: number; keys: string[]; lastX: number; points: number }[];
  signals(): string[];
  stats(): { fieldDraws: number; rawDrawn: number; robotsDrawn: number };
}

export async function world(page: Page): Promise<World> {
  const r = await page.request.get("/api/world");
  expect(r.ok()).toBeTruthy();
  return (await r.json()) as World;
}

export async function robot(page: Page, team: string, id: number): Promise<Robot> {
  return (await world(page)).robots.find((r) => r.team === team && r.id === id)!;
}

/** Opens the dashboard and waits until it streams and both teams are seen. */
export async function open(page: Page): Promise<void> {
  await page.goto("/");
  await expect(page.getByTestId("connection-status")).toContainText("connected");
  await expect.poll(async () => (await world(page)).robots.filter((r) => r.visible).length, { timeout: 30_000 })
    .toBeGreaterThanOrEqual(12);
}

/** A field point in mm as page coordinates (for mouse clicks on the canvas). */
export async function toScreen(page: Page, x: number, y: number): Promise<{ x: number; y: number }> {
  const box = (await page.getByTestId("field-canvas").boundingBox())!;
  const p = await page.evaluate(([xx, yy]) => (window as unknown as { __touchline: Hooks }).__touchline.worldToScreen(xx, yy), [x, y]);
  return { x: box.x + p.x, y: box.y + p.y };
}

export const stats = (page: Page) =>
  page.evaluate(() => (window as unknown as { __touchline: Hooks }).__touchline.stats());
