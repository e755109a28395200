import { expect, test } from "@playwright/test";
import { clickField, open, robot, stats, toasts, world } from "./helpers";

// Per-robot controller and filter choices, field layers and filter parameters, against the
// real station. The station is shared by every spec: each test puts back what it changed.

test("Algorithm 1 chosen in the robot panel drives a robot to a clicked point; the panel shows its C", async ({ page }) => {
  await open(page);
  await page.getByTestId("robot-row-blue-5").click();
  await expect(page.getByTestId("selected-robot")).toContainText("blue 5");
  const select = page.getByTestId("robot-controller-select");
  await expect(select).toBeEnabled();
  await expect(select.locator("option").first()).toHaveText(/^Default \((Algorithm [12]|Proportional)\)$/);
  let target = { x: -600, y: -2200 }; // own half, off the demo formation
  try {
    await select.selectOption("algorithm1");
    await expect(page.getByTestId("robot-controller-effective")).toHaveAttribute("data-override", "true");
    const values = (await (await page.request.get("/api/params")).json()).values;
    expect(values.control.robots["blue/5"].algorithm).toBe("algorithm1");
    await expect.poll(async () => (await robot(page, "blue", 5)).control?.algorithm ?? null).toBe("algorithm1");

    // a spot of our half no robot and no toast covers (otherwise the click selects or misses)
    target = await clickField(page, [target, { x: -1500, y: -2200 }, { x: -600, y: 2200 }, { x: -2000, y: 1500 }]);
    await expect(page.getByTestId("selected-robot")).toContainText("blue 5");
    await expect.poll(async () => {
      const source = (await robot(page, "blue", 5)).target?.source;
      return source ?? `no target (toasts: ${(await toasts(page)).join(" | ") || "none"})`;
    }).toBe("operator");
    const t = (await robot(page, "blue", 5)).target!;
    expect(Math.hypot(t.x - target.x, t.y - target.y)).toBeLessThan(40);
    await expect.poll(async () => {
      const r = await robot(page, "blue", 5);
      return Math.hypot(r.x - target.x, r.y - target.y);
    }, { timeout: 30_000, intervals: [250] }).toBeLessThan(150);

    expect((await robot(page, "blue", 5)).control?.algorithm).toBe("algorithm1");
    await expect(page.getByTestId("robot-controller-effective")).toHaveAttribute("data-value", "algorithm1");
    await expect(page.getByTestId("robot-algorithm")).toHaveText("Algorithm 1");
    await expect(page.getByTestId("robot-c-estimate")).toHaveText(/^-?\d+\.\d{3}$/);
    const c = Number(await page.getByTestId("robot-c-estimate").innerText());
    expect(c).toBeGreaterThan(0);

    // the one-click plots of the controller open on the Plots tab with its signals
    await page.getByTestId("robot-plot-controller").click();
    await expect(page.getByTestId("plots-panel")).toBeVisible();
    await expect(page.locator('[data-keys="robot.blue.5.control.c_estimate"]')).toHaveCount(1);
    await expect(page.locator('[data-keys="robot.blue.5.control.ref_x_m robot.blue.5.control.x_m"]')).toHaveCount(1);
    while (await page.getByRole("button", { name: "Remove plot" }).count()) await page.getByRole("button", { name: "Remove plot" }).first().click();

    // back to the default: the override is gone
    await page.getByTestId("tab-robots").click();
    await page.getByTestId("robot-controller-select").selectOption("");
    await expect.poll(async () => (await (await page.request.get("/api/params")).json()).values.control.robots["blue/5"] ?? null).toBeNull();
    await expect(page.getByTestId("robot-controller-effective")).toHaveAttribute("data-override", "false");
  } finally {
    await page.request.patch("/api/params", { data: { control: { robots: { "blue/5": null } } } });
    await page.request.delete("/api/robots/blue/5/target", { headers: { "X-Touchline": "1" } });
  }
});

test("layers toggle; the paper filter's weight from the Params tab; the paper filter for one robot", async ({ page }) => {
  await open(page);
  const schema = await (await page.request.get("/api/params/schema")).json();
  const wDefault = schema.$defs.PaperParams.properties.w_new.default as number;
  try {
    // raw detections layer: off by default, on draws the detections, off again draws none
    await page.getByTestId("layers-toggle").click();
    const raw = page.getByTestId("layer-toggle-raw");
    const before = await raw.isChecked();
    await raw.click();
    await expect(raw).toBeChecked({ checked: !before });
    await expect.poll(async () => (await stats(page)).rawDrawn > 0).toBe(!before);
    await raw.click();
    await expect(raw).toBeChecked({ checked: before });
    await expect.poll(async () => (await stats(page)).rawDrawn > 0).toBe(before);
    // filtered objects off: no robot drawn; on: all of them
    const filtered = page.getByTestId("layer-toggle-filtered");
    await expect(filtered).toBeChecked();
    await filtered.click();
    await expect(filtered).not.toBeChecked();
    await expect.poll(async () => (await stats(page)).robotsDrawn).toBe(0);
    await filtered.click();
    await expect(filtered).toBeChecked();
    await expect.poll(async () => (await stats(page)).robotsDrawn).toBeGreaterThanOrEqual(12);

    // filters.paper.w_new in the Params tab
    await page.getByTestId("tab-params").click();
    await page.getByTestId("params-filter").fill("w_new");
    const w = page.getByTestId("param-input-filters.paper.w_new");
    await w.fill("0.2");
    await w.press("Enter");
    await expect.poll(async () => (await (await page.request.get("/api/params")).json()).values.filters.paper.w_new).toBe(0.2);

    // the paper filter for blue 3, chosen in its panel
    await page.getByTestId("tab-robots").click();
    await page.getByTestId("robot-row-blue-3").click();
    await expect(page.getByTestId("selected-robot")).toContainText("blue 3");
    const sel = page.getByTestId("robot-filter-select");
    await expect(sel).toBeEnabled();
    await sel.selectOption("paper");
    await expect.poll(async () => (await robot(page, "blue", 3)).filter).toBe("paper");
    await expect(page.getByTestId("robot-filter-effective")).toHaveAttribute("data-value", "paper");
    await expect(page.getByTestId("robot-filter-effective")).toHaveAttribute("data-override", "true");
    expect((await robot(page, "blue", 2)).filter).not.toBe("paper"); // only this robot

    await sel.selectOption("");
    const def = (await (await page.request.get("/api/params")).json()).values.filters.robot as string;
    await expect.poll(async () => (await robot(page, "blue", 3)).filter).toBe(def);
    await expect(page.getByTestId("robot-filter-effective")).toHaveAttribute("data-override", "false");
  } finally {
    await page.request.patch("/api/params", { data: { filters: { paper: { w_new: wDefault }, robot_overrides: { "blue/3": null } } } });
  }
});
