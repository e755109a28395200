// @vitest-environment jsdom
// The team's code in the page: team plays in the Play selectors (grouped, following the
// folder without a reload), a robot's own play, and the Code tab's list, states, errors and
// notices. The station's routes are stood in for by a fetch stub (the Playwright spec
// team-code.spec.ts runs the same against the real station).
import { act } from "react";
import { beforeAll, describe, expect, it, vi } from "vitest";
import type { StrategyInfo, StrategyState, TeamCode, TeamFile } from "../api/types";
import { formStore } from "../params/paramsStore";
import { appStore, initialAppState } from "../store/appStore";
import { followTeamPlays, playsStore } from "../strategy/playsStore";
import { resetTeamStore } from "../team/teamStore";
import { domPerTest } from "../testing/dom";
import { health, strategyView, teamFile, world } from "../ws/fixtures";
import CodePanel from "./CodePanel";
import { PlaySelector } from "./PlaySelector";
import { RobotPlayChoice } from "./RobotPlayChoice";

(globalThis as { IS_REACT_ACT_ENVIRONMENT?: boolean }).IS_REACT_ACT_ENVIRONMENT = true;
// jsdom lays nothing out; CodeMirror measures text ranges (no layout: empty rectangles)
Range.prototype.getClientRects = () => Object.assign([] as DOMRect[], { item: () => null }) as unknown as DOMRectList;
Range.prototype.getBoundingClientRect = () => new DOMRect();

const connected = { status: "connected" as const, attempt: 0, retryAt: null, lastError: null };

const t = domPerTest(() => {
  appStore.setState(initialAppState());
  playsStore.setState({ info: null, error: null, loading: false, pending: null });
  formStore.setState({ groups: null, error: null, loading: false });
  resetTeamStore();
});
const q = t.q;

/** The lazily imported editor has mounted (its module is loaded before the tests: below). */
async function editorLoaded() {
  for (let i = 0; i < 50 && !t.host.querySelector(".cm-content"); i++) await settle();
  expect(t.host.querySelector(".cm-content")).not.toBeNull();
}

async function settle() {
  for (let i = 0; i < 6; i++) await act(async () => new Promise((r) => setTimeout(r, 0)));
}

type Handler = (body: unknown) => { status: number; body: unknown };

function stubApi(routes: Record<string, Handler>) {
  const fetchMock = vi.fn(async (url: string, init?: RequestInit) => {
    const h = routes[`${init?.method ?? "GET"} ${url}`];
    const r = h ? h(init?.body ? JSON.parse(String(init.body)) : undefined) : { status: 404, body: { detail: "Not Found" } };
    return new Response(JSON.stringify(r.body), { status: r.status });
  });
  vi.stubGlobal("fetch", fetchMock);
  return fetchMock;
}

const builtin = [
  { name: "match", title: "Match", description: "" },
  { name: "defend", title: "Defend", description: "" },
];
const teamPlay = (name: string, title: string) => ({ name, title, description: "", source: "team" as const, file: `${name}.py`, language: "python" as const });

const strategy = (extra: Partial<StrategyState> = {}): StrategyState => ({
  play: "pass_drill",
  situation: "running",
  situation_text: "",
  our_team: "blue",
  our_side: "negative-x",
  side_from_referee: false,
  tick_ms: 1,
  robot_plays: {},
  stopped: [],
  ...extra,
});

function groupsOf(el: HTMLSelectElement): [string, string[]][] {
  return [...el.querySelectorAll("optgroup")].map((g) => [g.label, [...g.querySelectorAll("option")].map((o) => o.textContent ?? "")]);
}

describe("team plays in the Play selector", () => {
  it("lists the team's plays in a group of their own, titles from the station", async () => {
    const info: StrategyInfo = strategyView([...builtin, teamPlay("pass_drill", "Pass drill")]);
    stubApi({ "GET /api/strategy": () => ({ status: 200, body: info }) });
    appStore.setState({ connection: connected, params: { version: 1, values: { strategy: { play: "pass_drill" } } } });
    act(() => t.root.render(<PlaySelector variant="bar" />));
    await settle();
    const el = q("play-select-bar") as HTMLSelectElement;
    expect(groupsOf(el)).toEqual([
      ["Built-in", ["Match", "Defend"]],
      ["Team", ["Pass drill"]],
    ]);
    expect(el.value).toBe("pass_drill");
  });

  it("follows a team play added to the folder (health.team_code) without a reload", async () => {
    let plays = [...builtin, teamPlay("pass_drill", "Pass drill")];
    const fetchMock = stubApi({ "GET /api/strategy": () => ({ status: 200, body: strategyView(plays) }) });
    const stop = followTeamPlays(appStore);
    try {
      const files = [teamFile("pass_drill.py", { kind: "play", play: "pass_drill", title: "Pass drill" })];
      appStore.setState({ connection: connected, health: { ...health(), team_code: files }, params: { version: 1, values: { strategy: { play: "match" } } } });
      act(() => t.root.render(<PlaySelector variant="bar" />));
      await settle();
      const el = () => q("play-select-bar") as HTMLSelectElement;
      expect(groupsOf(el())[1]).toEqual(["Team", ["Pass drill"]]);
      const strategyGets = () => fetchMock.mock.calls.filter(([u]) => u === "/api/strategy").length;
      const before = strategyGets();

      // a save that changes only code: nothing to fetch
      act(() => appStore.setState({ health: { ...health(), team_code: [{ ...files[0]!, version: "ffffffffffff" }] } }));
      await settle();
      expect(strategyGets()).toBe(before);

      // a new play file
      plays = [...plays, teamPlay("wall", "Wall")];
      act(() =>
        appStore.setState({ health: { ...health(), team_code: [...files, teamFile("wall.py", { kind: "play", play: "wall", title: "Wall" })] } }),
      );
      await settle();
      expect(strategyGets()).toBe(before + 1);
      expect(groupsOf(el())[1]).toEqual(["Team", ["Pass drill", "Wall"]]);
    } finally {
      stop();
    }
  });
});

describe("a robot's own play", () => {
  it("offers the team's play or any play, PATCHes strategy.robot_plays, and says when its play failed", async () => {
    const info = strategyView([...builtin, teamPlay("pass_drill", "Pass drill")]);
    const fetchMock = stubApi({
      "GET /api/strategy": () => ({ status: 200, body: info }),
      "PATCH /api/params": (body) => ({ status: 200, body: { version: 2, values: { strategy: { play: "match", robot_plays: { "3": "pass_drill" } } }, echo: body } }),
    });
    appStore.setState({
      connection: connected,
      params: { version: 1, values: { strategy: { play: "match", robot_plays: {} } } },
      world: world(1, { strategy: strategy({ play: "match", robot_plays: { "3": "match" } }) }),
    });
    act(() => t.root.render(<RobotPlayChoice robotKey={{ team: "blue", id: 3 }} />));
    await settle();
    const sel = q("robot-play-select") as HTMLSelectElement;
    expect(sel.options[0]!.textContent).toBe("Team's play (Match)");
    expect(sel.value).toBe("");
    expect(q("robot-play-effective")?.textContent).toBe("runs Match · team's");

    act(() => {
      sel.value = "pass_drill";
      sel.dispatchEvent(new Event("change", { bubbles: true }));
    });
    await settle();
    const patch = fetchMock.mock.calls.find(([, init]) => init?.method === "PATCH");
    expect(JSON.parse(String(patch?.[1]?.body))).toEqual({ strategy: { robot_plays: { "3": "pass_drill" } } });
    expect((q("robot-play-select") as HTMLSelectElement).value).toBe("pass_drill");

    act(() =>
      appStore.setState({
        world: world(2, {
          strategy: strategy({ play: "match", robot_plays: { "3": "pass_drill" }, stopped: [{ id: 3, play: "pass_drill", reason: "exception at pass_drill.py:7: boom" }] }),
        }),
      }),
    );
    const eff = q("robot-play-effective")!;
    expect(eff.getAttribute("data-stopped")).toBe("true");
    expect(eff.textContent).toBe("stopped: Pass drill failed · own");
    expect(eff.getAttribute("title")).toBe("play pass_drill failed, robot stopped: exception at pass_drill.py:7: boom");
  });

  it("is not offered for the other team's robots", async () => {
    stubApi({ "GET /api/strategy": () => ({ status: 200, body: strategyView(builtin) }) });
    appStore.setState({ connection: connected, params: { version: 1, values: { strategy: { play: "match" } } }, world: world(1, { strategy: strategy() }) });
    act(() => t.root.render(<RobotPlayChoice robotKey={{ team: "yellow", id: 3 }} />));
    await settle();
    expect(q("robot-play")).toBeNull();
  });
});

describe("the Code tab", () => {
  // CodeMirror's module, imported lazily by the tab, loaded once here (not inside a test's time)
  beforeAll(async () => {
    await import("./CodeEditor");
  }, 30_000);
  const err = {
    kind: "exception" as const,
    message: "ValueError: broken on purpose",
    file: "pass_drill.py",
    line: 7,
    traceback: 'Traceback (most recent call last):\n  File "pass_drill.py", line 7, in play\nValueError: broken on purpose',
    at_unix: 1_700_000_000,
  };
  const files: TeamFile[] = [
    teamFile("pass_drill.py", { kind: "play", play: "pass_drill", title: "Pass drill", state: "error", error: err, robots: [], reloads: 2 }),
    teamFile("keeper_wall.m", { kind: "play", play: "keeper_wall", title: "Keeper and wall", state: "running", robots: [0, 1], tick_ms_p50: 4.2, tick_ms_p99: 9.87, ticks: 500, overruns: 1, late: 3 }),
    teamFile("possession.py", { kind: "processor", title: "Ball possession", state: "running", outputs: { ours: 0.7 } }),
    teamFile("lib/geometry.py"),
  ];
  const SOURCE = ["from touchline import Target", "", "X = 1000.0", "", "", "def play(game):", '    raise ValueError("broken on purpose")', "    return {}", ""].join("\n");
  const team = (edit: TeamCode["edit"] = { allowed: true, reason: null }): TeamCode => ({ dir: "/home/me/team", api_version: 1, edit, files });

  function render(edit?: TeamCode["edit"]) {
    const fetchMock = stubApi({
      "GET /api/team": () => ({ status: 200, body: team(edit) }),
      "GET /api/strategy": () => ({ status: 200, body: strategyView(builtin) }),
      "GET /api/team/files/pass_drill.py": () => ({ status: 200, body: { name: "pass_drill.py", text: SOURCE, version: "aaaaaaaaaaaa", language: "python" } }),
      "PUT /api/team/files/pass_drill.py": () => ({ status: 200, body: { name: "pass_drill.py", version: "aaaaaaaaaaaa", saved_at_unix: 1_700_000_000 } }),
    });
    appStore.setState({
      connection: connected,
      health: { ...health(), team_code: files },
      world: world(1, { strategy: strategy({ stopped: [{ id: 4, play: "pass_drill", reason: "exception at pass_drill.py:7: ValueError: broken on purpose" }, { id: 2, play: "pass_drill", reason: "x" }] }) }),
    });
    act(() => t.root.render(<CodePanel />));
    return fetchMock;
  }

  it("lists the files grouped with their states, and opens the play in use with its error", async () => {
    render();
    await settle();
    expect([...t.host.querySelectorAll(".code-group h3")].map((h) => h.textContent)).toEqual(["Plays", "Processors", "Libraries"]);
    expect(q("code-state-pass_drill.py")?.getAttribute("data-state")).toBe("error");
    expect(q("code-state-pass_drill.py")?.getAttribute("title")).toBe("exception at pass_drill.py:7: ValueError: broken on purpose");
    expect(q("code-file-keeper_wall.m")?.textContent).toContain("0, 1");
    expect(q("code-dir")?.textContent).toBe("/home/me/team · API v1");

    // the play in use (world.strategy.play) is opened
    expect(q("code-file-pass_drill.py")?.getAttribute("aria-current")).toBe("true");
    expect(q("code-error")?.getAttribute("data-line")).toBe("7");
    expect(q("code-traceback")?.textContent).toContain('line 7, in play');
    expect(q("code-detail-stopped")?.textContent).toBe("robots 2, 4 (the play failed)");
    expect(q("code-stopped-pass_drill")?.getAttribute("data-ids")).toBe("2,4");
    expect(q("code-stopped")?.textContent).toContain("blue 2, 4 stopped");
    expect(q("code-save-status")?.getAttribute("data-dirty")).toBe("false");
    expect((q("code-save") as HTMLButtonElement).disabled).toBe(false);

    // the editor (loaded on demand) shows the file and marks the error's line
    await editorLoaded();
    const marked = [...t.host.querySelectorAll('.cm-line[data-error-line="true"]')].map((l) => l.textContent);
    expect(marked).toEqual(['    raise ValueError("broken on purpose")']);
    expect(t.host.querySelector(".cm-content")?.getAttribute("contenteditable")).toBe("true");
  });

  it("shows a processor's outputs with a plot button, and timing", async () => {
    render();
    await settle();
    act(() => (q("code-file-possession.py") as HTMLButtonElement).click());
    await settle();
    expect(q("code-detail-outputs")?.textContent).toContain("ours 0.700");
    expect(q("code-plot-ours")).not.toBeNull();
    act(() => (q("code-file-keeper_wall.m") as HTMLButtonElement).click());
    await settle();
    expect(q("code-detail-tick")?.textContent).toBe("p50 4.20 ms · p99 9.87 ms");
    expect(q("code-detail-robots")?.textContent).toBe("0, 1");
    // answers over the CPU budget apart from late ones (a busy machine)
    expect(q("code-detail-ticks")?.textContent).toBe("500 · 1 over budget · 3 late · 0 errors");
    act(() => (q("code-file-possession.py") as HTMLButtonElement).click());
    await settle();
    expect(q("code-detail-ticks")?.textContent).toBe("0 · 0 over budget · 0 errors");
  });

  it("saves the open file on Ctrl+S anywhere on the tab (PUT with the version it was opened at)", async () => {
    const fetchMock = render();
    await settle();
    await editorLoaded();
    act(() => {
      window.dispatchEvent(new KeyboardEvent("keydown", { key: "s", ctrlKey: true, cancelable: true }));
    });
    await settle();
    const put = fetchMock.mock.calls.find(([, init]) => init?.method === "PUT");
    expect(put?.[0]).toBe("/api/team/files/pass_drill.py");
    expect(JSON.parse(String(put?.[1]?.body))).toEqual({ text: SOURCE, base_version: "aaaaaaaaaaaa" });
  });

  it("is read-only with the station's reason when this browser may not edit", async () => {
    render({ allowed: false, reason: "saving code from another machine needs a station started with --allow-code-edit" });
    await settle();
    expect(q("code-readonly")?.textContent).toBe("Read-only: saving code from another machine needs a station started with --allow-code-edit");
    expect((q("code-save") as HTMLButtonElement).disabled).toBe(true);
    expect((q("code-new") as HTMLButtonElement).disabled).toBe(true);
    await editorLoaded();
    expect(t.host.querySelector(".cm-content")?.getAttribute("contenteditable")).toBe("false");
    expect(q("code-editor")?.getAttribute("data-readonly")).toBe("true");
  });
});
