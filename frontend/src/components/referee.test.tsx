// @vitest-environment jsdom
import { act } from "react";
import { beforeEach, describe, expect, it, vi } from "vitest";
import type { InternalReferee } from "../api/types";
import type { Health, RefereeGameEvent, RefereeHealth, Robot, Team } from "../api/types";
import { robot } from "../field/testRobots";
import { placementTarget, refereeSilentFor } from "../referee";
import { appStore, initialAppState } from "../store/appStore";
import { health, referee, refereeTeam, stream, world } from "../ws/fixtures";
import { HealthPanel } from "./HealthPanel";
import { HealthSummary } from "./HealthSummary";
import { EVENTS_SHOWN, fmtCards, RefereePanel, RefereeState } from "./RefereePanel";
import { Toasts } from "./Toasts";
import { TopBar } from "./TopBar";

import { domPerTest } from "../testing/dom";

(globalThis as { IS_REACT_ACT_ENVIRONMENT?: boolean }).IS_REACT_ACT_ENVIRONMENT = true;

const t = domPerTest();
const q = t.q;
const text = (id: string) => q(id)?.textContent ?? null;

/** `n` visible robots of `team`, plus one of that team the station no longer sees. */
function team(t: Team, n: number): Robot[] {
  const out = Array.from({ length: n }, (_, i) => robot(t, i, 100 * i, t === "blue" ? -500 : 500));
  out.push(robot(t, 15, 0, 0, { visible: false }));
  return out;
}

function event(type: string, by_team: string | null, origin: string[], id = type): RefereeGameEvent {
  return { id, type, by_team, origin, created_s: 1_700_000_000 };
}

/** What the official game controller sends during a yellow free kick after a foul. */
const gc = referee("STOP", {
  next_command: "DIRECT_FREE_YELLOW",
  status_message: "Robot substitution by blue",
  current_action_time_remaining_s: 7.46,
  designated_position: { x: 1500, y: -700 },
  blue: refereeTeam("Blue", {
    yellow_cards: 2,
    red_cards: 1,
    yellow_card_times_s: [41.2, 12],
    max_allowed_bots: 4,
    foul_counter: 2,
    can_place_ball: false,
    ball_placement_failures: 5,
  }),
  yellow: refereeTeam("Yellow", { max_allowed_bots: 6, foul_counter: 0, can_place_ball: true, ball_placement_failures: 0 }),
  game_events: [
    event("BOT_CRASH_UNIQUE", "BLUE", ["TIGERs AutoRef", "ER-Force"]),
    event("BALL_LEFT_FIELD_TOUCH_LINE", "YELLOW", ["UI"]),
    event("NO_PROGRESS_IN_GAME", null, []),
  ],
});

describe("RefereeState: what the game controller sends beyond the basics", () => {
  it("shows the next command, the status message and the action time left", () => {
    act(() => t.root.render(<RefereeState ref={gc} robots={[]} />));
    expect(text("referee-panel-command")).toBe("STOP");
    expect(text("referee-next")).toBe("DIRECT_FREE_YELLOW");
    expect(text("referee-status-message")).toBe("Robot substitution by blue");
    expect(text("referee-action-time")).toBe("7.5 s left");
    expect(q("referee-action-time")?.classList.contains("warn")).toBe(false);
  });

  it("marks an action time that ran out", () => {
    act(() => t.root.render(<RefereeState ref={{ ...gc, current_action_time_remaining_s: -3.04 }} />));
    expect(text("referee-action-time")).toBe("over by 3.0 s");
    expect(q("referee-action-time")?.classList.contains("warn")).toBe(true);
  });

  it("shows per team the robots allowed against those on the field, warning when there are too many", () => {
    // blue: 5 on the field, 4 allowed (two yellow cards); yellow: 6 of 6
    act(() => t.root.render(<RefereeState ref={gc} robots={[...team("blue", 5), ...team("yellow", 6)]} />));
    expect(text("referee-robots-blue")).toBe("5 / 4 allowed");
    expect(q("referee-robots-blue")?.classList.contains("warn")).toBe(true);
    expect(text("referee-robots-yellow")).toBe("6 / 6 allowed");
    expect(q("referee-robots-yellow")?.classList.contains("warn")).toBe(false);
    // a robot the station does not see does not count: 4 of 4 is fine
    act(() => t.root.render(<RefereeState ref={gc} robots={[...team("blue", 4), ...team("yellow", 6)]} />));
    expect(text("referee-robots-blue")).toBe("4 / 4 allowed");
    expect(q("referee-robots-blue")?.classList.contains("warn")).toBe(false);
  });

  it("shows cards with their seconds left, fouls and a team that cannot place the ball", () => {
    act(() => t.root.render(<RefereeState ref={gc} robots={[]} />));
    expect(text("referee-cards-blue")).toBe("2 yellow (41 s, 12 s) · 1 red");
    expect(text("referee-cards-yellow")).toBe("none");
    expect(text("referee-fouls-blue")).toBe("2");
    expect(text("referee-fouls-yellow")).toBe("0");
    expect(text("referee-placing-blue")).toBe("cannot place ball (5 failed)");
    expect(q("referee-placing-blue")?.classList.contains("warn")).toBe(true);
    expect(text("referee-placing-yellow")).toBe("—");
  });

  it("lists the recent game events newest first: type, team, origin", () => {
    act(() => t.root.render(<RefereeState ref={gc} robots={[]} />));
    const items = [...t.host.querySelectorAll('[data-testid="referee-event"]')].map((li) => li.textContent);
    expect(items).toEqual([
      "bot crash unique blue · TIGERs AutoRef, ER-Force",
      "ball left field touch line yellow · UI",
      "no progress in game",
    ]);
    const many = Array.from({ length: 8 }, (_, i) => event("BOT_CRASH_UNIQUE", "BLUE", ["UI"], `e${i}`));
    act(() => t.root.render(<RefereeState ref={{ ...gc, game_events: many }} robots={[]} />));
    expect(t.host.querySelectorAll('[data-testid="referee-event"]').length).toBe(EVENTS_SHOWN);
  });

  it("leaves out what a referee does not send (the internal referee, an older backend)", () => {
    act(() => t.root.render(<RefereeState ref={referee("HALT", { source: "internal" })} robots={team("blue", 6)} />));
    expect(text("referee-panel-command")).toBe("HALT");
    for (const id of ["referee-next", "referee-status-message", "referee-action-time", "referee-robots-blue", "referee-fouls-blue", "referee-placing-blue", "referee-events"]) {
      expect(q(id), id).toBeNull();
    }
    expect(text("referee-cards-blue")).toBe("none");
  });
});

describe("the ball placement target", () => {
  const mark = { x: 1500, y: -700 };

  it("is shown only during a ball placement, not the old mark the game controller sends during STOP", () => {
    act(() => t.root.render(<RefereeState ref={referee("STOP", { designated_position: mark })} />));
    expect(text("referee-placement")).toBe("—");
    act(() => t.root.render(<RefereeState ref={referee("BALL_PLACEMENT_YELLOW", { designated_position: mark })} />));
    expect(text("referee-placement")).toBe("1500, -700 mm");
  });

  it("placementTarget: the position during BALL_PLACEMENT_BLUE/YELLOW only", () => {
    expect(placementTarget(referee("BALL_PLACEMENT_BLUE", { designated_position: mark }))).toEqual(mark);
    expect(placementTarget(referee("BALL_PLACEMENT_YELLOW", { designated_position: mark }))).toEqual(mark);
    for (const cmd of ["STOP", "HALT", "TIMEOUT_YELLOW", "NORMAL_START", "PREPARE_KICKOFF_BLUE"] as const) {
      expect(placementTarget(referee(cmd, { designated_position: mark })), cmd).toBeNull();
    }
    expect(placementTarget(referee("BALL_PLACEMENT_BLUE"))).toBeNull();
    expect(placementTarget(referee("BALL_PLACEMENT_BLUE", { source: "none", designated_position: mark }))).toBeNull();
    expect(placementTarget(null)).toBeNull();
  });

  it("fmtCards ignores expired card times", () => {
    expect(fmtCards(refereeTeam("b", { yellow_cards: 1, yellow_card_times_s: [0] }))).toBe("1 yellow");
  });
});

describe("a silent referee", () => {
  const connected = { status: "connected" as const, attempt: 0, retryAt: null, lastError: null };
  const refHealth = (last_heard_s: number, silent: boolean): RefereeHealth => ({
    last_heard_s,
    source_identifier: "gc-1",
    source: "game-controller",
    command: "STOP",
    obeyed: true,
    silent,
    silent_after_s: 3,
  });
  const withReferee = (r: RefereeHealth | null, warnings: string[] = []): Health => ({
    ...health(60),
    streams: {
      ...health(60).streams,
      referee: stream({ packets: 900, rate_hz: r?.silent ? 0 : 40, last_age_s: r?.last_heard_s ?? -1 }),
    },
    referee: r,
    warnings,
  });

  beforeEach(() => appStore.setState(initialAppState()));

  it("shows 'referee silent N s' in the top bar and the health summary, and clears when it speaks again", () => {
    // the top bar samples the world (throttled): it is there before the first render
    appStore.setState({ connection: connected, world: world(1, { referee: referee("STOP") }), health: withReferee(refHealth(0.02, false)) });
    act(() => t.root.render(<><TopBar onRetryNow={() => {}} /><HealthSummary /></>));
    expect(q("referee-silent")).toBeNull();
    expect(q("health-summary-stream-referee")?.classList.contains("warn")).toBe(false);
    act(() => appStore.setState({ health: withReferee(refHealth(12.7, true), ["referee silent 12 s: still obeying STOP from gc-1"]) }));
    expect(text("referee-silent")).toBe("referee silent 12 s");
    // the last command is still shown: the station still obeys it
    expect(text("referee-command")).toBe("STOP");
    expect(text("health-summary-stream-referee")).toBe("0.0 Hz · silent 12 s");
    expect(q("health-summary-stream-referee")?.classList.contains("warn")).toBe(true);
    act(() => appStore.setState({ health: withReferee(refHealth(0.01, false)) }));
    expect(q("referee-silent")).toBeNull();
    expect(text("health-summary-stream-referee")).toBe("40.0 Hz");
  });

  it("says nothing for a referee the station ignores, none heard, or an older backend", () => {
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ health: withReferee({ ...refHealth(60, false), obeyed: false }) }));
    expect(q("referee-silent")).toBeNull();
    act(() => appStore.setState({ health: withReferee(null) }));
    expect(q("referee-silent")).toBeNull();
    act(() => appStore.setState({ health: health(60) }));
    expect(q("referee-silent")).toBeNull();
    expect(refereeSilentFor(null)).toBeNull();
  });

  it("lists the health warnings under the station's state", () => {
    act(() => t.root.render(<HealthPanel />));
    act(() => appStore.setState({ health: withReferee(refHealth(4.2, true), ["referee silent 4 s: still obeying STOP from gc-1"]) }));
    expect([...t.host.querySelectorAll('[data-testid="health-warnings"] li')].map((li) => li.textContent)).toEqual([
      "referee silent 4 s: still obeying STOP from gc-1",
    ]);
    act(() => appStore.setState({ health: withReferee(refHealth(0.1, false)) }));
    expect(q("health-warnings")).toBeNull();
  });
});

describe("the internal referee's card buttons", () => {
  const internal = (over: Partial<InternalReferee> = {}): InternalReferee => ({
    enabled: true,
    disabled_reason: "",
    foreign_source: null,
    command: "FORCE_START",
    stage: "NORMAL_FIRST_HALF",
    command_counter: 3,
    designated_position: null,
    score: { blue: 0, yellow: 0 },
    max_allowed_bots: { blue: 6, yellow: 6 },
    commands: ["HALT", "STOP", "FORCE_START"],
    ...over,
  });

  type Reply = { status: number; body: unknown };
  /** The internal referee's state as the world message brings it, and fetch for
   * POST /api/referee/internal/card (`card` answers it; the panel polls nothing). */
  function stubApi(state: InternalReferee, card: (body: { team: string; card: string }) => Reply) {
    appStore.setState({ world: world(1, { internal_referee: state }) });
    const fetchMock = vi.fn(async (url: string, init?: RequestInit) => {
      const key = `${init?.method ?? "GET"} ${url}`;
      const r: Reply =
        key === "POST /api/referee/internal/card"
            ? card(JSON.parse(String(init?.body)))
            : { status: 404, body: { detail: "Not Found" } };
      return new Response(JSON.stringify(r.body), { status: r.status });
    });
    vi.stubGlobal("fetch", fetchMock);
    return fetchMock;
  }
  const posted = (fetchMock: ReturnType<typeof stubApi>) =>
    fetchMock.mock.calls
      .filter(([url, init]) => url === "/api/referee/internal/card" && init?.method === "POST")
      .map(([, init]) => ({ type: (init?.headers as Record<string, string>)["Content-Type"], body: JSON.parse(String(init?.body)) }));

  /** Let pending fetches and the renders they cause finish. */
  async function settle() {
    for (let i = 0; i < 5; i++) await act(async () => new Promise((r) => setTimeout(r, 0)));
  }
  const click = async (id: string) => {
    const b = q(id) as HTMLButtonElement | null;
    expect(b, id).not.toBeNull();
    act(() => b!.click());
    await settle();
  };
  const toasts = () => [...t.host.querySelectorAll('[data-testid="toast"]')].map((el) => [el.getAttribute("data-kind"), el.querySelector("span")?.textContent]);

  beforeEach(() => appStore.setState(initialAppState()));

  it("has a yellow card, red card and clear cards button per team, named for screen readers", async () => {
    const fetchMock = stubApi(internal(), () => ({ status: 200, body: { internal: internal() } }));
    act(() => t.root.render(<RefereePanel />));
    await settle();
    expect(fetchMock).not.toHaveBeenCalled(); // its state comes with the world: no polling
    for (const team of ["blue", "yellow"]) {
      for (const [card, name] of [["yellow", "Yellow card"], ["red", "Red card"], ["clear", "Clear cards"]]) {
        const b = q(`ref-card-${card}-${team}`) as HTMLButtonElement;
        expect(b.textContent).toBe(team);
        expect(b.getAttribute("aria-label")).toBe(`${name} for ${team}`);
        expect(b.title.startsWith(`${name} for ${team}: `)).toBe(true);
        expect(b.disabled).toBe(false);
      }
    }
  });

  it("posts {team, card} for each button", async () => {
    const fetchMock = stubApi(internal(), () => ({ status: 200, body: { internal: internal() } }));
    act(() => t.root.render(<RefereePanel />));
    await settle();
    await click("ref-card-yellow-blue");
    await click("ref-card-red-yellow");
    await click("ref-card-clear-blue");
    await click("ref-card-yellow-yellow");
    await click("ref-card-red-blue");
    await click("ref-card-clear-yellow");
    expect(posted(fetchMock)).toEqual([
      { type: "application/json", body: { team: "blue", card: "yellow" } },
      { type: "application/json", body: { team: "yellow", card: "red" } },
      { type: "application/json", body: { team: "blue", card: "clear" } },
      { type: "application/json", body: { team: "yellow", card: "yellow" } },
      { type: "application/json", body: { team: "blue", card: "red" } },
      { type: "application/json", body: { team: "yellow", card: "clear" } },
    ]);
    expect(q("referee-error")).toBeNull();
  });

  it("shows a 409 (a game controller is active) under the buttons and as an error toast", async () => {
    const detail = "a game controller is active (gc-1): the internal referee stays off";
    stubApi(internal(), () => ({ status: 409, body: { detail } }));
    act(() => t.root.render(<><RefereePanel /><Toasts /></>));
    await settle();
    await click("ref-card-yellow-blue");
    expect(text("referee-error")).toBe(`${detail} (HTTP 409)`);
    expect(toasts()).toContainEqual(["error", `Referee yellow card for blue: ${detail} (HTTP 409)`]);
  });

  it("shows a 422 with the server's field message; a later success clears it", async () => {
    let reply: Reply = { status: 422, body: { detail: [{ loc: ["body", "card"], msg: "Input should be 'yellow', 'red' or 'clear'" }] } };
    stubApi(internal(), () => reply);
    act(() => t.root.render(<><RefereePanel /><Toasts /></>));
    await settle();
    await click("ref-card-clear-yellow");
    expect(text("referee-error")).toBe("card: Input should be 'yellow', 'red' or 'clear' (HTTP 422)");
    expect(toasts()).toContainEqual(["error", "Referee clear cards for yellow: card: Input should be 'yellow', 'red' or 'clear' (HTTP 422)"]);
    reply = { status: 200, body: { internal: internal() } };
    await click("ref-card-clear-yellow");
    expect(q("referee-error")).toBeNull();
  });

  it("is disabled while a game controller has the say", async () => {
    const fetchMock = stubApi(internal({ enabled: false, foreign_source: "gc-1" }), () => ({ status: 200, body: {} }));
    act(() => t.root.render(<RefereePanel />));
    await settle();
    for (const id of ["ref-card-yellow-blue", "ref-card-red-yellow", "ref-card-clear-blue"]) {
      expect((q(id) as HTMLButtonElement).disabled, id).toBe(true);
    }
    await click("ref-card-yellow-blue");
    expect(posted(fetchMock)).toEqual([]);
  });
});
