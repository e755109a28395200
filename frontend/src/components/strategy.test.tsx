// @vitest-environment jsdom
import { act } from "react";
import { describe, expect, it, vi } from "vitest";
import type { StrategyInfo, StrategyState } from "../api/types";
import { robot } from "../field/testRobots";
import { formStore } from "../params/paramsStore";
import { appStore, initialAppState } from "../store/appStore";
import { playsStore } from "../strategy/playsStore";
import { engineHealth, health, strategyView, world } from "../ws/fixtures";
import { EnginePanel } from "./HealthPanel";
import { HealthSummary } from "./HealthSummary";
import { PlaySelector } from "./PlaySelector";
import { RobotDetails } from "./RobotDetails";
import { RobotTable } from "./RobotTable";
import { SituationBanner } from "./SituationBanner";
import { Toasts } from "./Toasts";

import { domPerTest } from "../testing/dom";

(globalThis as { IS_REACT_ACT_ENVIRONMENT?: boolean }).IS_REACT_ACT_ENVIRONMENT = true;

const connected = { status: "connected" as const, attempt: 0, retryAt: null, lastError: null };

const t = domPerTest(() => {
  appStore.setState(initialAppState());
  playsStore.setState({ info: null, error: null, loading: false, pending: null });
  formStore.setState({ groups: null, error: null, loading: false });
});
const q = t.q;

/** Let pending fetches and the renders they cause finish. */
async function settle() {
  for (let i = 0; i < 5; i++) await act(async () => new Promise((r) => setTimeout(r, 0)));
}

const strategyInfo: StrategyInfo = strategyView([
    { name: "match", title: "Match", description: "Full game with a keeper, attackers and defenders" },
    { name: "defend", title: "Defend", description: "Park the bus" },
    { name: "formation", title: "Classroom formation", description: "The formation demo" },
  ]);

type Handler = (method: string, body: unknown) => { status: number; body: unknown };

/** A fetch for the station's API: GET /api/strategy, GET /api/params/schema, PATCH /api/params. */
function stubApi(routes: Record<string, Handler>) {
  const fetchMock = vi.fn(async (url: string, init?: RequestInit) => {
    const method = init?.method ?? "GET";
    const handler = routes[`${method} ${url}`];
    const r = handler ? handler(method, init?.body ? JSON.parse(String(init.body)) : undefined) : { status: 404, body: { detail: "Not Found" } };
    return new Response(JSON.stringify(r.body), { status: r.status });
  });
  vi.stubGlobal("fetch", fetchMock);
  return fetchMock;
}

function select(): HTMLSelectElement {
  return q("play-select-bar") as HTMLSelectElement;
}

function choose(el: HTMLSelectElement, value: string) {
  act(() => {
    el.value = value;
    el.dispatchEvent(new Event("change", { bubbles: true }));
  });
}

describe("PlaySelector", () => {
  it("lists the plays by title, the current one selected, its description as help", async () => {
    stubApi({ "GET /api/strategy": () => ({ status: 200, body: strategyInfo }) });
    appStore.setState({ connection: connected, params: { version: 3, values: { strategy: { play: "defend" } } } });
    act(() => t.root.render(<PlaySelector variant="bar" />));
    await settle();
    const el = select();
    expect(el.getAttribute("aria-label")).toBe("Play");
    expect([...el.options].map((o) => o.textContent)).toEqual(["Match", "Defend", "Classroom formation"]);
    expect(el.value).toBe("defend");
    expect(el.title).toBe("Park the bus");
    expect(document.getElementById(el.getAttribute("aria-describedby")!)?.textContent).toBe("Park the bus");
  });

  it("PATCHes strategy.play and follows the server's answer", async () => {
    const fetchMock = stubApi({
      "GET /api/strategy": () => ({ status: 200, body: strategyInfo }),
      "PATCH /api/params": (_m, body) => ({ status: 200, body: { version: 4, values: body } }),
    });
    appStore.setState({ connection: connected, params: { version: 3, values: { strategy: { play: "match" } } } });
    act(() => t.root.render(<PlaySelector variant="bar" />));
    await settle();
    choose(select(), "formation");
    await settle();
    const patch = fetchMock.mock.calls.find(([, init]) => init?.method === "PATCH");
    expect(patch?.[0]).toBe("/api/params");
    expect(JSON.parse(String(patch?.[1]?.body))).toEqual({ strategy: { play: "formation" } });
    expect(appStore.getState().params?.values).toEqual({ strategy: { play: "formation" } });
    expect(select().value).toBe("formation");
  });

  it("shows the server's reason as a toast when the play is refused and keeps the current one", async () => {
    stubApi({
      "GET /api/strategy": () => ({ status: 200, body: strategyInfo }),
      "PATCH /api/params": () => ({
        status: 422,
        body: { detail: [{ loc: ["body", "strategy", "play"], msg: "the referee holds the game: no drills now" }] },
      }),
    });
    appStore.setState({ connection: connected, params: { version: 3, values: { strategy: { play: "match" } } } });
    act(() =>
      t.root.render(
        <>
          <PlaySelector variant="bar" />
          <Toasts />
        </>,
      ),
    );
    await settle();
    choose(select(), "defend");
    await settle();
    const toast = t.host.querySelector('[data-testid="toast"][data-kind="error"]');
    expect(toast?.textContent).toContain('Play "Defend" refused');
    expect(toast?.textContent).toContain("the referee holds the game: no drills now");
    expect(select().value).toBe("match");
  });

  it("falls back to the enum of the play parameter when the station has no /api/strategy", async () => {
    stubApi({
      "GET /api/params/schema": () => ({
        status: 200,
        body: {
          type: "object",
          properties: {
            strategy: { type: "object", properties: { play: { type: "string", enum: ["match", "attack-drill", "idle"], default: "match" } } },
          },
        },
      }),
    });
    appStore.setState({ connection: connected, params: { version: 1, values: { strategy: { play: "idle" } } } });
    act(() => t.root.render(<PlaySelector variant="panel" />));
    await settle();
    const el = q("play-select-panel") as HTMLSelectElement;
    expect([...el.options].map((o) => o.value)).toEqual(["match", "attack-drill", "idle"]);
    expect([...el.options].map((o) => o.textContent)).toEqual(["Match", "Attack drill", "Idle"]);
    expect(el.value).toBe("idle");
  });

  it("renders nothing for a station without strategy", async () => {
    stubApi({});
    appStore.setState({ connection: connected });
    act(() => t.root.render(<PlaySelector variant="bar" />));
    await settle();
    expect(t.host.innerHTML).toBe("");
  });
});

describe("EnginePanel and the health summary", () => {
  it("says engine off without an engine (field null or absent)", () => {
    act(() => t.root.render(<EnginePanel h={health()} />));
    expect(q("engine-panel")?.getAttribute("data-engine")).toBe("off");
    expect(q("engine-off")?.textContent).toContain("engine off");
    act(() => t.root.render(<EnginePanel h={{ ...health(), engine: null }} />));
    expect(q("engine-off")).not.toBeNull();
    expect(q("engine-details")).toBeNull();
  });

  it("shows every number and the last error when there is one", () => {
    act(() => t.root.render(<EnginePanel h={{ ...health(), engine: engineHealth({ fallbacks: 7 }) }} />));
    expect(q("engine-panel")?.getAttribute("data-engine")).toBe("octave");
    expect(q("engine-kind")?.textContent).toBe("octave");
    expect(q("engine-function")?.textContent).toBe("goalkeeper");
    expect(q("engine-rate")?.textContent).toBe("20.0");
    expect(q("engine-latency")?.textContent).toBe("3.21 ms / 11.5 ms");
    expect(q("engine-workers")?.textContent).toBe("2: 1 busy / 1 idle");
    expect(q("engine-fallbacks")?.textContent).toBe("7");
    expect(q("engine-fallbacks")?.className).toContain("warn");
    expect(q("engine-last-error")).toBeNull();
    act(() => t.root.render(<EnginePanel h={{ ...health(), engine: engineHealth({ last_error: "goalkeeper.m: undefined 'ball_x'" }) }} />));
    expect(q("engine-last-error")?.getAttribute("role")).toBe("alert");
    expect(q("engine-last-error")?.textContent).toContain("goalkeeper.m: undefined 'ball_x'");
  });

  it("puts the engine in the health summary", () => {
    appStore.setState({ health: health() });
    act(() => t.root.render(<HealthSummary />));
    expect(q("health-summary-engine")?.textContent).toBe("off");
    act(() => appStore.setState({ health: { ...health(), engine: engineHealth({ kind: "numpy", timeouts: 2 }) } }));
    expect(q("health-summary-engine")?.textContent).toBe("numpy 20/s · 2 err");
  });
});

describe("roles in the robot table and panel, situation banner", () => {
  it("shows the role tag with the full name on hover, nothing without a role", () => {
    const robots = [robot("blue", 0, 0, 0, { role: "goalkeeper" }), robot("blue", 1, 0, 0), robot("yellow", 0, 0, 0, { role: null })];
    act(() => t.root.render(<RobotTable robots={robots} selected={null} />));
    const cell = q("robot-row-blue-0")!.querySelector('[data-testid="robot-role"]')!;
    expect(cell.textContent).toBe("GK");
    expect(cell.getAttribute("title")).toBe("Goalkeeper");
    expect(cell.getAttribute("data-role")).toBe("goalkeeper");
    expect(q("robot-row-blue-1")!.querySelector('[data-testid="robot-role"]')!.textContent).toBe("");
  });

  it("shows a robot leaving the field for a substitution as SUB (Substitution on hover)", () => {
    const robots = [robot("blue", 3, -300, 2900, { role: "substitution" })];
    act(() => t.root.render(<RobotTable robots={robots} selected={null} />));
    const cell = q("robot-row-blue-3")!.querySelector('[data-testid="robot-role"]') as HTMLElement;
    expect(cell.textContent).toBe("SUB");
    expect(cell.getAttribute("title")).toBe("Substitution");
    expect(cell.getAttribute("data-role")).toBe("substitution");
    expect(cell.style.color).not.toBe("");
    act(() => t.root.render(<RobotDetails selected={{ team: "blue", id: 3 }} robot={robots[0]!} />));
    expect(q("robot-role-detail")?.textContent).toBe("Substitution (SUB)");
  });

  it("shows role, path, kicker and dribbler of the selected robot", () => {
    const r = robot("blue", 4, 0, 0, {
      role: "attacker",
      path: [{ x: 300, y: 400 }, { x: 300, y: 1400 }],
      kick: { speed_mps: 4, chip: true },
      dribbler: true,
    });
    act(() => t.root.render(<RobotDetails selected={{ team: "blue", id: 4 }} robot={r} />));
    expect(q("robot-role-detail")?.textContent).toBe("Attacker (ATK)");
    expect(q("robot-path")?.textContent).toBe("2 waypoints · 1.50 m");
    expect(q("robot-kick")?.textContent).toBe("armed 4.0 m/s chip");
    expect(q("robot-dribbler")?.textContent).toBe("on");
    // not repeated among the extra fields
    expect(q("robot-extra-role")).toBeNull();
    expect(q("robot-extra-path")).toBeNull();
  });

  it("says so for a robot the strategy gives nothing", () => {
    act(() => t.root.render(<RobotDetails selected={{ team: "blue", id: 4 }} robot={robot("blue", 4, 0, 0)} />));
    expect(q("robot-role-detail")?.textContent).toBe("—");
    expect(q("robot-path")?.textContent).toBe("—");
    expect(q("robot-kick")?.textContent).toBe("not armed");
    expect(q("robot-dribbler")?.textContent).toBe("off");
  });

  it("banners the situation and the side we defend", () => {
    const strategy: StrategyState = {
      play: "match",
      situation: "stop",
      situation_text: "STOP: keep 0.5 m from the ball",
      our_team: "yellow",
      our_side: "positive-x",
      side_from_referee: true,
      tick_ms: 2,
      robot_plays: {},
      stopped: [],
    };
    act(() => t.root.render(<SituationBanner />));
    expect(q("situation-banner")).toBeNull();
    act(() => appStore.setState({ world: world(1, { strategy }) }));
    expect(q("situation-banner")?.getAttribute("data-situation")).toBe("stop");
    expect(q("situation-text")?.textContent).toBe("STOP: keep 0.5 m from the ball");
    expect(q("situation-side")?.textContent).toBe("we defend the +x goal (right), side from the referee");
  });
});
