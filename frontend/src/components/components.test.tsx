// @vitest-environment jsdom
import { act } from "react";
import { describe, expect, it, vi } from "vitest";
import { robot } from "../field/testRobots";
import { appStore, initialAppState } from "../store/appStore";
import { arming, health, world } from "../ws/fixtures";
import { RobotDetails } from "./RobotDetails";
import { RobotTable } from "./RobotTable";
import { TopBar } from "./TopBar";
import { AccessHealth, ArmingHealth, Cameras, ErrorsByReason, EstopHealth, Latency, Processes } from "./HealthPanel";
import { FRAME_AGE_STAGE } from "../api/contract.gen";
import { toastTexts } from "../store/toasts";

import { domPerTest } from "../testing/dom";

(globalThis as { IS_REACT_ACT_ENVIRONMENT?: boolean }).IS_REACT_ACT_ENVIRONMENT = true;

const t = domPerTest(() => appStore.setState(initialAppState()));
const q = t.q;

describe("RobotTable", () => {
  const robots = [
    robot("yellow", 2, 1000.4, -250.6, { visible: false }),
    robot("blue", 3, -1234.5, 987.2, { target: { x: 10, y: -20, orientation: null, source: "operator" } }),
  ];

  it("renders one row per robot with the stable test ids, blue first", () => {
    act(() => t.root.render(<RobotTable robots={robots} selected={{ team: "blue", id: 3 }} />));
    expect(q("robot-table")).not.toBeNull();
    const rows = t.host.querySelectorAll('[data-testid^="robot-row-"]');
    expect([...rows].map((r) => r.getAttribute("data-testid"))).toEqual(["robot-row-blue-3", "robot-row-yellow-2"]);
    const blue = q("robot-row-blue-3")!;
    expect(blue.getAttribute("data-visible")).toBe("true");
    expect(blue.getAttribute("data-selected")).toBe("true");
    expect(blue.querySelector('[data-testid="robot-x"]')?.textContent).toBe("-1234");
    expect(blue.querySelector('[data-testid="robot-y"]')?.textContent).toBe("987");
    expect(blue.querySelector('[data-testid="robot-target"]')?.textContent).toBe("10, -20");
    const yellow = q("robot-row-yellow-2")!;
    expect(yellow.getAttribute("data-visible")).toBe("false");
    expect(yellow.querySelector('[data-testid="robot-x"]')?.textContent).toBe("1000");
    expect(yellow.querySelector('[data-testid="robot-y"]')?.textContent).toBe("-251");
  });

  it("selects a robot when its row is clicked", () => {
    act(() => t.root.render(<RobotTable robots={robots} selected={null} />));
    act(() => (q("robot-row-yellow-2") as HTMLElement).click());
    expect(appStore.getState().selected).toEqual({ team: "yellow", id: 2 });
  });
});

describe("RobotTable: ball contact", () => {
  const fb = {
    transport: "sim" as const, ball_contact: true, age_s: 0.01, no_answer: false, last_kick: null, last_kick_age_s: null,
    round_trip_ms: 0.5, commands_sent: 200, answers: 190, loss: 0.05, battery_v: null, kicker_v: null,
  };

  it("shows the ball contact each robot reports, '!' when it does not answer, nothing without feedback", () => {
    const robots = [
      robot("blue", 0, 0, 0, { feedback: fb }),
      robot("blue", 1, 0, 0, { feedback: { ...fb, ball_contact: false } }),
      robot("blue", 2, 0, 0, { feedback: { ...fb, no_answer: true, age_s: 0.8 } }),
      robot("yellow", 0, 0, 0),
    ];
    act(() => t.root.render(<RobotTable robots={robots} selected={null} />));
    const cell = (key: string) => q(`robot-row-${key}`)!.querySelector('[data-testid="robot-ball"]')!;
    expect(cell("blue-0").getAttribute("data-contact")).toBe("true");
    expect(cell("blue-0").textContent).toBe("◉");
    expect(cell("blue-1").getAttribute("data-state")).toBe("free");
    expect(cell("blue-2").getAttribute("data-state")).toBe("no-answer");
    expect(cell("blue-2").textContent).toBe("!");
    expect(cell("blue-2").getAttribute("title")).toBe("no answer for 0.8 s");
    expect(cell("yellow-0").getAttribute("data-state")).toBe("none");
    expect(cell("yellow-0").textContent).toBe("");
  });

  it("shows the feedback age, round trip and losses in the details, 'no answer' when silent", () => {
    act(() => t.root.render(<RobotDetails selected={{ team: "blue", id: 0 }} robot={robot("blue", 0, 0, 0, { feedback: fb })} />));
    expect(q("robot-ball-contact")?.textContent).toBe("yes");
    expect(q("robot-feedback")?.textContent).toBe("0.01 s ago (sim)");
    expect(q("robot-round-trip")?.textContent).toBe("0.5 ms");
    expect(q("robot-loss")?.textContent).toBe("5 % (190 of 200 answered, 2 s)");
    expect(q("robot-battery")).toBeNull();
    expect(q("robot-extra-feedback")).toBeNull();
    const silent = { ...fb, no_answer: true, age_s: 1.25, battery_v: 15.9, last_kick: "chip" as const, last_kick_age_s: 3 };
    act(() => t.root.render(<RobotDetails selected={{ team: "blue", id: 0 }} robot={robot("blue", 0, 0, 0, { feedback: silent })} />));
    expect(q("robot-feedback")?.textContent).toBe("no answer for 1.25 s");
    expect(q("robot-ball-contact")?.textContent).toBe("unknown (no answer)");
    expect(q("robot-battery")?.textContent).toBe("15.9 V");
    expect(q("robot-last-kick")?.textContent).toBe("chip 3.0 s ago");
    act(() => t.root.render(<RobotDetails selected={{ team: "blue", id: 0 }} robot={robot("blue", 0, 0, 0)} />));
    expect(q("robot-feedback")?.textContent).toBe("—");
  });
});

describe("RobotDetails", () => {
  it("shows 'team id' for the selection", () => {
    act(() => t.root.render(<RobotDetails selected={{ team: "blue", id: 3 }} robot={robot("blue", 3, 0, 0)} />));
    expect(q("selected-robot")?.textContent).toBe("blue 3");
    act(() => t.root.render(<RobotDetails selected={null} robot={null} />));
    expect(q("selected-robot")?.textContent).toBe("No robot selected");
  });
});

describe("TopBar", () => {
  it("shows connection, vision rate and the e-stop state from the store", () => {
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    expect(q("connection-status")?.textContent).not.toContain("connected");
    expect(q("vision-rate")?.textContent).toBe("— Hz");
    expect(q("estop-button")?.textContent).toBe("EMERGENCY STOP");
    act(() =>
      appStore.setState({
        connection: { status: "connected", attempt: 0, retryAt: null, lastError: null },
        health: health(59.66),
        world: world(1, { estop: true }),
      }),
    );
    expect(q("connection-status")?.textContent).toContain("connected");
    expect(q("vision-rate")?.textContent).toBe("59.7 Hz");
    expect(q("estop-button")?.textContent).toBe("Release");
    act(() =>
      appStore.setState({ connection: { status: "reconnecting", attempt: 2, retryAt: null, lastError: "closed" } }),
    );
    expect(q("connection-status")?.textContent).toContain("reconnecting");
    expect(q("connection-status")?.textContent).not.toContain("connected");
  });
});

describe("Processes", () => {
  it("shows each process's CPU and memory, and their sum", () => {
    act(() => t.root.render(<Processes h={health()} />));
    expect(q("health-process-backend")?.textContent).toBe("backend23.5 %120 MB");
    expect(q("health-process-relay")?.textContent).toBe("relay11.2 %40 MB");
    expect(q("health-processes")?.closest("section")?.textContent).toContain("together 35 %");
    expect(q("health-restarts-relay")?.textContent).toBe("");
    const crashed = { ...health(), supervisor: [{ name: "relay", pid: 7, restarts: 2, last_exit: -9, up_s: 3 }] };
    act(() => t.root.render(<Processes h={crashed} />));
    expect(q("health-restarts-relay")?.textContent).toBe("2 restarts");
    act(() => t.root.render(<Processes h={{ ...health(), processes: [] }} />));
    expect(q("health-processes")).toBeNull();
  });
});

describe("Latency", () => {
  it("shows the age of each robot's newest frame when its command is sent, '—' before there is one", () => {
    const row = (name: string) =>
      [...t.host.querySelectorAll('[data-testid="health-latency"] tr')].find((r) => r.textContent?.startsWith(name))?.textContent;
    act(() => t.root.render(<Latency h={health()} />));
    expect(row("robot's newest frame p50")).toBe("robot's newest frame p50—");
    const stage = { stage: FRAME_AGE_STAGE, mean_ms: 1.1, p50_ms: 0.64, p99_ms: 12.5, n: 900 };
    const other = { stage: "vision -> world", mean_ms: 0.2, p50_ms: 0.2, p99_ms: 0.3, n: 900 };
    act(() => t.root.render(<Latency h={{ ...health(), latency_stages: [other, stage] }} />));
    expect(row("robot's newest frame p50")).toBe("robot's newest frame p500.64 ms");
    expect(row("robot's newest frame p99")).toBe("robot's newest frame p9912.50 ms");
  });
});

describe("Cameras", () => {
  it("shows each camera pair's offset, marked when large, and the clock offsets", () => {
    act(() => t.root.render(<Cameras h={health()} />));
    expect(q("health-camera-pairs")).toBeNull();
    const world = {
      age_s: 0.01, stale: false, rejected: {}, recent_rejections: {}, last_rejection: "", clock_resyncs: 0,
      camera_clock_offsets_s: { "0": 0, "1": 0.002 },
      camera_pairs: [
        { camera_a: 0, camera_b: 1, dx_mm: 24.96, dy_mm: -10.04, samples: 200 },
        { camera_a: 1, camera_b: 3, dx_mm: 1.2, dy_mm: 0.4, samples: 50 },
      ],
      camera_rates_hz: { "0": 60.02, "1": 0 },
      lost_after_s: 0.08,
      vision_lost: null,
    };
    act(() => t.root.render(<Cameras h={{ ...health(), world }} />));
    const far = q("health-camera-pair-0-1")!;
    expect(far.textContent).toContain("25.0, -10.0 mm");
    expect(far.querySelector(".warn")).not.toBeNull();
    expect(q("health-camera-pair-1-3")!.querySelector(".warn")).toBeNull();
    expect(q("health-camera-clocks")?.textContent).toBe("cam 0: 0.000 · cam 1: 0.002");
    expect(q("health-camera-rates")?.textContent).toBe("cam 0: 60 Hz · cam 1: — · all silent: robots stopped after 80 ms");
    expect(q("health-camera-rates")?.className).toBe("muted");
    const lost = { ...world, lost_after_s: null, vision_lost: "no vision: every camera silent for 95 ms (was 60 Hz)" };
    act(() => t.root.render(<Cameras h={{ ...health(), world: lost }} />));
    expect(q("health-camera-rates")?.textContent).toBe(
      "cam 0: 60 Hz · cam 1: — · all silent: robots stopped after safety.vision_stale_s · no vision: every camera silent for 95 ms (was 60 Hz)",
    );
    expect(q("health-camera-rates")?.className).toBe("warn");
  });
});

describe("ErrorsByReason", () => {
  it("lists refused datagrams per stream and reason, and nothing when there are none", () => {
    const h = health();
    act(() => t.root.render(<ErrorsByReason h={h} />));
    expect(q("health-errors")).toBeNull();
    h.streams = {
      vision: { packets: 100, rate_hz: 60, last_age_s: 0.01, errors: 3, errors_by_reason: { truncated: 2, "time out of range": 1 }, last_error: "time out of range: camera 0" },
      "relay.referee": { packets: 5, errors: 1, errors_by_reason: { "not protobuf": 1 }, rate_hz: 20, last_age_s: 0.1, last_error: "not protobuf" },
    };
    act(() => t.root.render(<ErrorsByReason h={{ ...h }} />));
    expect(q("health-error-vision-truncated")?.textContent).toBe("visiontruncated2");
    expect(q("health-error-vision-time-out-of-range")?.getAttribute("title")).toBe("time out of range: camera 0");
    expect(q("health-error-relay.referee-not-protobuf")?.textContent).toContain("1");
  });
});

describe("Emergency stop release", () => {
  it("asks before releasing, sends the confirmation, and presses in one click", async () => {
    const fetchMock = vi.fn(async () => new Response('{"estop": false}'));
    vi.stubGlobal("fetch", fetchMock);
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ world: world(1, { estop: true }) }));
    act(() => (q("estop-button") as HTMLButtonElement).click());
    expect(q("estop-release-dialog")).not.toBeNull();
    expect(fetchMock).not.toHaveBeenCalled();
    act(() => (q("estop-release-cancel") as HTMLButtonElement).click());
    expect(q("estop-release-dialog")).toBeNull();
    expect(fetchMock).not.toHaveBeenCalled();
    act(() => (q("estop-button") as HTMLButtonElement).click());
    await act(async () => (q("estop-release-confirm") as HTMLButtonElement).click());
    expect(fetchMock).toHaveBeenCalledTimes(1);
    const [, init] = fetchMock.mock.calls[0] as unknown as [string, RequestInit];
    expect(JSON.parse(String(init.body))).toEqual({ active: false, confirm: true });
    // pressing: no dialog, one request
    act(() => appStore.setState({ world: world(1, { estop: false }) }));
    await act(async () => (q("estop-button") as HTMLButtonElement).click());
    expect(q("estop-release-dialog")).toBeNull();
    const [, press] = fetchMock.mock.calls[1] as unknown as [string, RequestInit];
    expect(JSON.parse(String(press.body))).toEqual({ active: true });
  });
});

describe("AccessHealth", () => {
  it("says who may do what, what was refused and whether someone is blocked", () => {
    const h = health();
    act(() => t.root.render(<AccessHealth h={h} />));
    expect(q("health-access")?.textContent).toBe("Access: no token needed (loopback)");
    const access = { token_required: true, view_token: false, estop_for_all: true, refused: { "no operator token": 3, "wrong token": 12 }, blocked_clients: 1 };
    act(() => t.root.render(<AccessHealth h={{ ...h, access }} />));
    const text = q("health-access")?.textContent ?? "";
    expect(text).toContain("changes need the operator token, every viewer may press the e-stop");
    expect(text).toContain("refused: no operator token 3, wrong token 12");
    expect(text).toContain("1 address blocked for wrong tokens");
    expect(q("health-access")?.className).toBe("notice");
  });
});

describe("EstopHealth", () => {
  it("says whether the stop is active, since when, by whom, and whether the relay latched it", () => {
    const h = health();
    const since = Date.UTC(2026, 0, 1, 12, 0, 0) / 1000;
    act(() => t.root.render(<EstopHealth h={{ ...h, estop: { active: true, since, by: "operator at 10.0.0.9", relay_latched: true } }} />));
    const p = q("health-estop");
    expect(p?.getAttribute("data-active")).toBe("true");
    expect(p?.textContent).toContain("Emergency stop ACTIVE since");
    expect(p?.textContent).toContain("(operator at 10.0.0.9)");
    expect(p?.textContent).toContain("latched in the relay");
    act(() => t.root.render(<EstopHealth h={{ ...h, estop: { active: true, since, by: "", relay_latched: false } }} />));
    expect(q("health-estop")?.textContent).toContain("not latched in the relay");
    act(() => t.root.render(<EstopHealth h={{ ...h, estop: { active: false, since: 0, by: "", relay_latched: null } }} />));
    expect(q("health-estop")?.getAttribute("data-active")).toBe("false");
    expect(q("health-estop")?.textContent).toBe("Emergency stop released · relay latch unknown");
  });
});

describe("Arming", () => {
  const disarmed = () => world(1, { armed: false, arming_required: true, arming: arming({ required: true, armed: false, refusal: "vision is missing" }) });
  const armed = () => world(1, { armed: true, arming_required: true, arming: arming({ required: true, armed: true, by: "operator at 127.0.0.1" }) });

  it("shows nothing where arming is not required (the built-in simulator)", () => {
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ world: world(1) }));
    expect(q("arm-state")).toBeNull();
    expect(q("arm-button")).toBeNull();
  });

  it("shows disarmed in grey and ARMED in red", () => {
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ world: disarmed() }));
    expect(q("arm-state")?.textContent).toBe("disarmed");
    expect(q("arm-state")?.parentElement?.className).toContain("arm-disarmed");
    expect(q("arm-button")?.textContent).toBe("Arm…");
    act(() => appStore.setState({ world: armed() }));
    expect(q("arm-state")?.textContent).toBe("ARMED");
    expect(q("arm-state")?.getAttribute("data-armed")).toBe("true");
    expect(q("arm-state")?.parentElement?.className).toContain("arm-armed");
    expect(q("arm-button")?.textContent).toBe("Disarm");
  });

  it("asks before arming, names our team, and sends the arming after the confirmation", async () => {
    const fetchMock = vi.fn(async () => new Response(JSON.stringify(arming({ required: true, armed: true }))));
    vi.stubGlobal("fetch", fetchMock);
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    const w = disarmed();
    w.strategy = { play: "idle", situation: "", situation_text: "", our_team: "blue", our_side: "negative-x", side_from_referee: false, tick_ms: 0, robot_plays: {}, stopped: [] };
    act(() => appStore.setState({ world: w }));
    act(() => (q("arm-button") as HTMLButtonElement).click());
    expect(q("arm-dialog")?.textContent).toContain("Robots will move: arm blue?");
    expect(fetchMock).not.toHaveBeenCalled();
    act(() => (q("arm-cancel") as HTMLButtonElement).click());
    expect(q("arm-dialog")).toBeNull();
    expect(fetchMock).not.toHaveBeenCalled();
    act(() => (q("arm-button") as HTMLButtonElement).click());
    await act(async () => (q("arm-confirm") as HTMLButtonElement).click());
    expect(fetchMock).toHaveBeenCalledTimes(1);
    const [url, init] = fetchMock.mock.calls[0] as unknown as [string, RequestInit];
    expect(url).toContain("/api/arm");
    expect(JSON.parse(String(init.body))).toEqual({ armed: true });
    expect(q("arm-state")?.textContent).toBe("ARMED"); // the answer, before the next world
  });

  it("disarms in one click", async () => {
    const fetchMock = vi.fn(async () => new Response(JSON.stringify(arming({ required: true, armed: false }))));
    vi.stubGlobal("fetch", fetchMock);
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ world: armed() }));
    await act(async () => (q("arm-button") as HTMLButtonElement).click());
    expect(q("arm-dialog")).toBeNull();
    const [, init] = fetchMock.mock.calls[0] as unknown as [string, RequestInit];
    expect(JSON.parse(String(init.body))).toEqual({ armed: false });
    expect(q("arm-state")?.textContent).toBe("disarmed");
  });

  it("shows the server's refusal as a toast and stays disarmed", async () => {
    const fetchMock = vi.fn(async () => new Response(JSON.stringify({ detail: "the emergency stop is active: release it first" }), { status: 409 }));
    vi.stubGlobal("fetch", fetchMock);
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ world: disarmed() }));
    act(() => (q("arm-button") as HTMLButtonElement).click());
    await act(async () => (q("arm-confirm") as HTMLButtonElement).click());
    const toasts = toastTexts().join("\n");
    expect(toasts).toContain("the emergency stop is active: release it first");
    expect(q("arm-state")?.textContent).toBe("disarmed");
  });

  it("health says armed or not and what the relay says", () => {
    const h = health();
    act(() => t.root.render(<ArmingHealth h={h} />));
    expect(q("health-arming")).toBeNull();
    act(() => t.root.render(<ArmingHealth h={{ ...h, arming: arming({ required: true, armed: false, relay_armed: false, refusal: "vision is missing" }) }} />));
    expect(q("health-arming")?.textContent).toBe("Disarmed: only stops reach the robots · relay disarmed · arming refused now: vision is missing");
    act(() => t.root.render(<ArmingHealth h={{ ...h, arming: arming({ required: true, armed: true, relay_armed: true, by: "op" }) }} />));
    expect(q("health-arming")?.getAttribute("data-armed")).toBe("true");
    expect(q("health-arming")?.textContent).toContain("relay armed");
  });
});
