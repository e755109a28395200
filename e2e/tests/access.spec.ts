import type { ChildProcess } from "node:child_process";
import { expect, test } from "@playwright/test";
import { startTokenStation, stopStation } from "./helpers";

// The operator token on a station that requires it (docs/security.md): a station of its own,
// started with --require-token (no simulator), beside the one the config starts. A browser
// that opened the printed login URL works as on loopback (the cookie goes with every request
// and the websocket); a second browser without it is told how to log in when it tries a change.

const port = Number(process.env.E2E_PORT ?? "18000") + 7;
const base = `http://127.0.0.1:${port}`;
let station: ChildProcess | null = null;
let loginUrl = "";

test.beforeAll(async () => {
  test.setTimeout(90_000);
  ({ proc: station, loginUrl } = await startTokenStation(port, ["--sim", "none"]));
});

test.afterAll(async () => {
  await stopStation(station);
});

test("the login URL makes an operator; a browser without it is told how to log in", async ({ browser }) => {
  expect(loginUrl.startsWith(`${base}/login?token=`)).toBeTruthy();
  const operator = await browser.newContext({ baseURL: base });
  const op = await operator.newPage();
  await op.goto(loginUrl);
  await expect(op).toHaveURL(`${base}/`);
  await expect(op.getByTestId("connection-status")).toContainText("connected");
  await op.getByTestId("tab-referee").click();
  await op.getByTestId("ref-STOP").click();
  await expect(op.getByTestId("referee-command")).toHaveText("STOP");
  await expect(op.getByTestId("toast").filter({ hasText: "Not logged in" })).toHaveCount(0);

  const stranger = await browser.newContext({ baseURL: base });
  const other = await stranger.newPage();
  await other.goto("/");
  // viewing stays open: the page streams
  await expect(other.getByTestId("connection-status")).toContainText("connected");
  await other.getByTestId("tab-referee").click();
  await other.getByTestId("ref-HALT").click();
  const toast = other.getByTestId("toast").filter({ hasText: "Not logged in" });
  await expect(toast).toHaveCount(1);
  await expect(toast).toContainText("/login?token=");
  await expect(toast).toContainText("operator token");
  // nothing changed: the operator's STOP stands
  await expect(op.getByTestId("referee-command")).toHaveText("STOP");
  const r = await other.request.post("/api/referee/internal/command", { data: { command: "HALT" } });
  expect(r.status()).toBe(401);
  await operator.close();
  await stranger.close();
});

test("team code: a browser without the operator token sees the code read-only, with the reason; the operator may save", async ({ browser }) => {
  const stranger = await browser.newContext({ baseURL: base });
  const other = await stranger.newPage();
  await other.goto("/");
  await expect(other.getByTestId("connection-status")).toContainText("connected");
  await other.getByTestId("tab-code").click();
  await other.getByTestId("code-file-pass_drill.py").click();
  await expect(other.locator(".cm-content")).toContainText("Pass drill");
  await expect(other.getByTestId("code-readonly")).toContainText("requires the operator token");
  await expect(other.getByTestId("code-editor")).toHaveAttribute("data-readonly", "true");
  await expect(other.locator(".cm-content")).toHaveAttribute("contenteditable", "false");
  await expect(other.getByTestId("code-save")).toBeDisabled();
  await expect(other.getByTestId("code-new")).toBeDisabled();
  await stranger.close();

  // the operator (logged in, on loopback) may edit
  const operator = await browser.newContext({ baseURL: base });
  const op = await operator.newPage();
  await op.goto(loginUrl);
  await expect(op.getByTestId("connection-status")).toContainText("connected");
  await op.getByTestId("tab-code").click();
  await op.getByTestId("code-file-pass_drill.py").click();
  await expect(op.locator(".cm-content")).toHaveAttribute("contenteditable", "true");
  await expect(op.getByTestId("code-readonly")).toHaveCount(0);
  await expect(op.getByTestId("code-save")).toBeEnabled();
  await operator.close();
});
