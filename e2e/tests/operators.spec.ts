import type { ChildProcess } from "node:child_process";
import { expect, test, type Page } from "@playwright/test";
import { startTokenStation, stopStation, type World } from "./helpers";

// Several operators (issue 12, docs/security.md): a station of its own with --require-token
// and a relay that sends nothing until armed (--require-arming), beside the one the config
// starts. Two browsers log in with the printed URL and a name; the second takes over driving
// after confirming; arming and disarming; the simulator's ball contact in the robot table; the
// operator action list says who did what.

const port = Number(process.env.E2E_PORT ?? "18000") + 8;
const base = `http://127.0.0.1:${port}`;
let station: ChildProcess | null = null;
let loginUrl = "";

test.beforeAll(async () => {
  test.setTimeout(90_000);
  ({ proc: station, loginUrl } = await startTokenStation(port, ["--relay-arg=--require-arming"]));
});

test.afterAll(async () => {
  await stopStation(station);
});

const world = async (page: Page) => (await (await page.request.get("/api/world")).json()) as World;

/** Logs in with the printed URL and a name; waits until the page streams the simulator. */
async function login(page: Page, name: string): Promise<void> {
  await page.goto(`${loginUrl}&name=${name}`);
  await expect(page).toHaveURL(`${base}/`);
  await expect(page.getByTestId("connection-status")).toContainText("connected");
  await expect(page.getByTestId("name-prompt")).toHaveCount(0); // the login gave the name
  await expect.poll(async () => (await world(page)).robots.filter((r) => r.visible).length, { timeout: 30_000 }).toBeGreaterThanOrEqual(12);
  await page.getByTestId("tab-health").click();
  await expect(page.getByTestId("my-name")).toHaveText(name);
}

test("two operators: driving taken over after confirming, asked and given back; arm, disarm, ball contact", async ({ browser }) => {
  test.setTimeout(120_000);
  const a = await browser.newContext({ baseURL: base });
  const b = await browser.newContext({ baseURL: base });
  const alice = await a.newPage();
  const bob = await b.newPage();
  await login(alice, "alice");
  await login(bob, "bob");
  // both pages are listed, with their names
  for (const page of [alice, bob]) {
    await expect(page.getByTestId("operator-row").filter({ hasText: "alice" })).toHaveCount(1);
    await expect(page.getByTestId("operator-row").filter({ hasText: "bob" })).toHaveCount(1);
  }

  // alice drives first (the play, a target): blue is hers
  expect((await alice.request.patch("/api/params", { data: { strategy: { play: "idle" } } })).status()).toBe(200);
  const ours = (await world(alice)).strategy?.our_team ?? "blue";
  expect((await alice.request.post(`/api/robots/${ours}/1/target`, { data: { x: -500, y: 500 } })).status()).toBe(200);
  await expect(bob.getByTestId(`driving-${ours}`)).toHaveAttribute("data-holder", "alice");
  await expect(alice.getByTestId(`driving-${ours}`)).toHaveAttribute("data-mine", "true");
  // bob is refused, told who drives
  const refused = await bob.request.post(`/api/robots/${ours}/2/target`, { data: { x: 500, y: 500 } });
  expect(refused.status()).toBe(409);
  expect(((await refused.json()) as { detail: string }).detail).toContain("alice");

  // bob takes over, after confirming on the page
  await bob.getByTestId(`driving-take-${ours}`).click();
  await bob.getByTestId(`driving-take-cancel-${ours}`).click(); // changed his mind once
  await expect(bob.getByTestId(`driving-${ours}`)).toHaveAttribute("data-holder", "alice");
  await bob.getByTestId(`driving-take-${ours}`).click();
  await bob.getByTestId(`driving-take-confirm-${ours}`).click();
  await expect(bob.getByTestId(`driving-${ours}`)).toHaveAttribute("data-mine", "true");
  await expect(alice.getByTestId(`driving-${ours}`)).toHaveAttribute("data-holder", "bob");
  await expect(alice.getByTestId("operator-action").filter({ hasText: "driving-taken-over" }).first()).toContainText("bob");
  expect((await alice.request.post(`/api/robots/${ours}/1/target`, { data: { x: 0, y: 0 } })).status()).toBe(409);

  // alice asks; bob's page shows it with an accept; she drives again
  await alice.getByTestId(`driving-ask-${ours}`).click();
  const ask = bob.getByTestId("driving-request");
  await expect(ask).toContainText(`alice asks to drive ${ours}`);
  await ask.getByTestId("driving-give").click();
  await expect(alice.getByTestId(`driving-${ours}`)).toHaveAttribute("data-mine", "true");
  await expect(ask).toHaveCount(0);

  // arm (after the confirmation) and see the simulator's ball contact: robot 0 holds still
  // with the ball put at its kicker (contact is reported once commands reach the simulator)
  await expect(alice.getByTestId("arm-state")).toHaveAttribute("data-armed", "false");
  await alice.getByTestId("arm-button").click();
  await alice.getByTestId("arm-confirm").click();
  await expect(alice.getByTestId("arm-state")).toHaveAttribute("data-armed", "true");
  await expect(bob.getByTestId("arm-state")).toHaveAttribute("data-armed", "true");
  const put = async () => {
    expect((await alice.request.post(`/api/sim/robots/${ours}/0`, { data: { x: -2000, y: 1000, orientation: 0 } })).status()).toBe(200);
    expect((await alice.request.post(`/api/robots/${ours}/0/target`, { data: { x: -2000, y: 1000, orientation: 0 } })).status()).toBe(200);
    expect((await alice.request.post("/api/sim/ball", { data: { x: -1885, y: 1000 } })).status()).toBe(200);
  };
  await put();
  await alice.getByTestId("tab-robots").click();
  const ball = alice.getByTestId(`robot-row-${ours}-0`).getByTestId("robot-ball");
  await expect(async () => {
    if ((await ball.getAttribute("data-contact")) !== "true") await put();
    await expect(ball).toHaveAttribute("data-contact", "true", { timeout: 3_000 });
  }).toPass({ timeout: 30_000 });

  // disarm: one click
  await alice.getByTestId("arm-button").click();
  await expect(alice.getByTestId("arm-state")).toHaveAttribute("data-armed", "false");

  // every action, with who, in the list on the page
  await bob.getByTestId("tab-health").click();
  const seen: [string, string][] = [["disarm", "alice"], ["arm", "alice"], ["driving-given", "bob"],
    ["driving-requested", "alice"], ["driving-taken-over", "bob"], ["target", "alice"], ["play", "alice"]];
  for (const [action, by] of seen) {
    await expect(bob.locator(`[data-testid="operator-action"][data-action="${action}"]`).first()).toContainText(by);
  }
  await a.close();
  await b.close();
});
