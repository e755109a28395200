// Helpers shared by the end-to-end specs: the world as /api/world reports it, opening the
// page once the station streams, and the page's test hooks (window.__touchline).
import { spawn, type ChildProcess } from "node:child_process";
import { expect, type Page } from "@playwright/test";

export interface Control { algorithm: string; phase: string; c_estimate: number }
export interface Robot {
  team: string; id: number; x: number; y: number; vx: number; vy: number; visible: boolean;
  filter?: string; control?: Control | null;
  target: { x: number; y: number; orientation: number | null; source: string } | null;
  /** Strategy (absent on a station without it): role, planned waypoints, kicker, dribbler. */
  role?: string | null; path?: { x: number; y: number }[] | null;
  kick?: { speed_mps: number; chip: boolean } | null; dribbler?: boolean;
  /** The velocity the station commands (robot frame), null when not commanded. */
  command?: { forward_mps: number; left_mps: number; angular_radps: number } | null;
}
export interface Strategy {
  play: string; situation: string; situation_text: string; our_team: "blue" | "yellow";
  our_side: "negative-x" | "positive-x"; side_from_referee: boolean; tick_ms: number;
}
export interface World {
  robots: Robot[]; ball: { x: number; y: number } | null; estop: boolean;
  referee: { source: string; command: string; designated_position?: { x: number; y: number } | null } | null;
  strategy?: Strategy | null;
}

export interface Hooks {
  worldToScreen(x: number, y: number): { x: number; y: number };
  plots(): { id: number; keys: string[]; lastX: number; points: number }[];
  signals(): string[];
  stats(): {
    fieldDraws: number; rawDrawn: number; robotsDrawn: number; pathsDrawn: number; rolesDrawn: number;
    /** The ball placement mark the last field frame drew (world mm), null when none. */
    designatedDrawn: { x: number; y: number } | null;
    /** Objects of the estimate recorded in a replayed log the last field frame drew. */
    recordedDrawn: number;
    /** Our robots the last field frame marked as stopped by a failed team-code play ("blue 3"). */
    stoppedDrawn: string[];
    /** Command arrows the last field frame drew (replay's what-if). */
    commandsDrawn: number;
    /** Arrows of the replayed log's own commands the last field frame drew (beside those). */
    recordedCommandsDrawn: number;
  };
  /** The world the page holds (as received over the websocket). */
  getWorld(): World | null;
  strategy(): Strategy | null;
  roles(ours?: boolean): { team: string; id: number; role: string | null }[];
  paths(): { team: string; id: number; path: { x: number; y: number }[] | null }[];
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

/** The toasts the page shows now ("kind: text"), for failure messages. */
export const toasts = (page: Page): Promise<string[]> =>
  page.getByTestId("toast").evaluateAll((els) => els.map((e) => `${e.getAttribute("data-kind")}: ${e.querySelector("span")?.textContent ?? ""}`));

/** Clicks the field at the first of ``candidates`` (mm) that the pointer really reaches (no
 * toast or panel over that spot of the canvas) and that no robot of the page's world is within
 * ``clearMm`` of (a click there would select that robot instead): returns the point clicked.
 * Fails naming what was in the way of each candidate. */
export async function clickField(
  page: Page,
  candidates: { x: number; y: number }[],
  clearMm = 400,
): Promise<{ x: number; y: number }> {
  const why: string[] = [];
  for (const c of candidates) {
    const s = await toScreen(page, c.x, c.y);
    const blocked = await page.evaluate(([x, y, cx, cy, clear]) => {
      const el = document.elementFromPoint(x, y);
      if (el?.getAttribute("data-testid") !== "field-canvas") {
        return `under ${el ? el.getAttribute("data-testid") ?? `${el.tagName.toLowerCase()}.${el.className}` : "nothing"}`;
      }
      const w = (window as unknown as { __touchline: Hooks }).__touchline.getWorld();
      const near = (w?.robots ?? []).filter((r) => r.visible && Math.hypot(r.x - cx, r.y - cy) < clear);
      return near.length ? `robots near: ${near.map((r) => `${r.team} ${r.id}`).join(", ")}` : null;
    }, [s.x, s.y, c.x, c.y, clearMm] as const);
    if (blocked === null) {
      await page.mouse.click(s.x, s.y);
      return c;
    }
    why.push(`(${c.x}, ${c.y}) ${blocked}`);
  }
  throw new Error(`no spot of the field to click: ${why.join("; ")}; toasts: ${(await toasts(page)).join(" | ") || "none"}`);
}

export const stats = (page: Page) =>
  page.evaluate(() => (window as unknown as { __touchline: Hooks }).__touchline.stats());

/** Roles of our robots in the latest world the page holds (our team from the world's strategy). */
export const ourRoles = (page: Page) =>
  page.evaluate(() => (window as unknown as { __touchline: Hooks }).__touchline.roles(true).map((r) => r.role));

/** A station of a spec's own (launcher --isolated on ``port`` with ``args``), started with
 * --require-token: resolves with the process and the operator's login URL it printed. */
export async function startTokenStation(
  port: number,
  args: string[],
): Promise<{ proc: ChildProcess; loginUrl: string }> {
  const root = new URL("../..", import.meta.url).pathname;
  const proc = spawn(
    `${root}.venv/bin/python`,
    ["-m", "launcher", "--isolated", "--port", String(port), "--require-token", ...args],
    { cwd: root, env: { ...process.env, PYTHONUNBUFFERED: "1" }, stdio: ["ignore", "pipe", "pipe"] },
  );
  const loginUrl = await new Promise<string>((resolve, reject) => {
    const timer = setTimeout(() => {
      // not left running behind a failed test (the launcher stops its children with it)
      proc.kill("SIGTERM");
      reject(new Error("the station printed no login URL"));
    }, 80_000);
    let url = "";
    let buf = "";
    proc.stdout?.on("data", (chunk: Buffer) => {
      buf += chunk.toString();
      for (const line of buf.split("\n")) {
        if (line.startsWith("TOUCHLINE_LOGIN ")) {
          const info = JSON.parse(line.slice("TOUCHLINE_LOGIN ".length)) as { role: string; url: string };
          if (info.role === "operator") url = info.url;
        }
        if (line.startsWith("TOUCHLINE_READY ") && url) {
          clearTimeout(timer);
          resolve(url);
        }
      }
    });
    proc.stderr?.resume();
    proc.on("exit", (code) => reject(new Error(`the station exited (${code})`)));
  });
  return { proc, loginUrl };
}

/** Stops a station started by ``startTokenStation`` (SIGTERM, SIGKILL after 15 s). */
export async function stopStation(proc: ChildProcess | null): Promise<void> {
  if (!proc || proc.exitCode !== null) return;
  const gone = new Promise((resolve) => proc.on("exit", resolve));
  proc.kill("SIGTERM");
  await Promise.race([gone, new Promise((resolve) => setTimeout(resolve, 15_000))]);
  if (proc.exitCode === null) proc.kill("SIGKILL");
}
