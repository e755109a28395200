// @vitest-environment jsdom
import { act } from "react";
import { describe, expect, it, vi } from "vitest";
import type { Player, Referee } from "../api/types";
import { speedStore } from "../player/actions";
import { appStore, initialAppState } from "../store/appStore";
import { domPerTest } from "../testing/dom";
import { health, logPlayer, player, recording, refereeTeam, replayClock, world } from "../ws/fixtures";
import { RecordIndicator } from "./PlayerBar";
import { Timeline } from "./Timeline";
import { TopBar } from "./TopBar";

(globalThis as { IS_REACT_ACT_ENVIRONMENT?: boolean }).IS_REACT_ACT_ENVIRONMENT = true;

const t = domPerTest(() => {
  appStore.setState(initialAppState());
  speedStore.setState({ pending: null });
});
const q = t.q;

/** fetch answering every request with `reply` (JSON); the calls are recorded. */
function stubFetch(reply: (url: string, init: RequestInit) => unknown) {
  const fn = vi.fn(async (url: string, init: RequestInit) => new Response(JSON.stringify(reply(url, init))));
  vi.stubGlobal("fetch", fn);
  return fn;
}

function sent(fn: ReturnType<typeof stubFetch>, i: number): { url: string; method: string; body: unknown; headers: unknown } {
  const [url, init] = fn.mock.calls[i] as unknown as [string, RequestInit];
  return { url, method: String(init.method), body: init.body ? JSON.parse(String(init.body)) : undefined, headers: init.headers };
}

function showLog(p: Partial<Player> = {}, replay = replayClock()) {
  act(() => appStore.setState({ player: logPlayer(p), world: world(1, { replay }) }));
}

function pointer(el: Element, type: string, clientX: number) {
  el.dispatchEvent(new MouseEvent(type, { bubbles: true, cancelable: true, clientX, button: 0 }));
}

describe("Timeline", () => {
  it("is hidden when live and shown with a log", () => {
    act(() => t.root.render(<Timeline />));
    expect(q("timeline")).toBeNull();
    act(() => appStore.setState({ player: player() }));
    expect(q("timeline")).toBeNull();
    showLog();
    expect(q("timeline")).not.toBeNull();
  });

  it("renders one marker per event with its kind, label and place on the bar", () => {
    act(() => t.root.render(<Timeline />));
    showLog();
    const markers = [...t.host.querySelectorAll('[data-testid="timeline-marker"]')] as HTMLElement[];
    expect(markers.map((m) => m.getAttribute("data-kind"))).toEqual(["command", "goal", "stage", "card"]);
    expect(markers[1]!.getAttribute("title")).toContain("goal blue");
    expect(markers[2]!.style.left).toBe("50%");
    // the playhead is at 0:30: the jump buttons name their events
    expect(q("timeline-prev-event")?.getAttribute("title")).toBe("Previous event: FORCE_START (command) at 0:10.0");
    expect(q("timeline-next-event")?.getAttribute("title")).toBe("Next event: goal blue (goal) at 0:40.0");
  });

  it("shows the position, the log's wall time and the stage", () => {
    act(() => t.root.render(<Timeline />));
    const referee: Referee = {
      source: "game-controller", source_identifier: "", command: "STOP", stage: "NORMAL_FIRST_HALF", command_counter: 1,
      stage_time_left_s: 125, blue: refereeTeam("A"), yellow: refereeTeam("B"), designated_position: null,
      blue_team_on_positive_half: null, next_command: null, status_message: "", match_type: null,
      current_action_time_remaining_s: null, game_events: [], age_s: 0,
    };
    const tUnix = new Date(2026, 0, 2, 14, 3, 4).getTime() / 1000;
    act(() =>
      appStore.setState({
        player: logPlayer(),
        world: world(1, { replay: replayClock({ position_s: 75.25, t_unix: tUnix }), referee }),
      }),
    );
    expect(q("timeline-position")?.textContent).toBe("1:15.2 / 2:00");
    expect(q("timeline-wall")?.textContent).toBe("14:03:04");
    expect(q("timeline-stage")?.textContent).toBe("normal first half 2:05");
  });

  it("trusts the player's position until the first world of a new epoch arrives", async () => {
    act(() => t.root.render(<Timeline />));
    showLog({ epoch: 5, position_s: 90 }, replayClock({ epoch: 4, position_s: 12 }));
    expect(q("timeline-position")?.textContent).toBe("1:30.0 / 2:00");
    act(() => appStore.setState({ world: world(2, { replay: replayClock({ epoch: 5, position_s: 90.5 }) }) }));
    // the timeline samples the world at 10 Hz
    await act(async () => new Promise((r) => setTimeout(r, 150)));
    expect(q("timeline-position")?.textContent).toBe("1:30.5 / 2:00");
  });

  it("shows the player's error and warning", () => {
    act(() => t.root.render(<Timeline />));
    showLog({ error: "seek past the end", warning: "truncated tail" });
    expect(q("timeline-error")?.textContent).toBe("seek past the end");
    expect(q("timeline-warning")?.textContent).toContain("truncated tail");
  });

  it("seeks to the clicked position on the bar", async () => {
    const fetchMock = stubFetch(() => logPlayer({ position_s: 30 }));
    act(() => t.root.render(<Timeline />));
    showLog();
    const bar = q("timeline-bar") as HTMLElement;
    bar.getBoundingClientRect = () => ({ left: 100, width: 400, top: 0, height: 26, right: 500, bottom: 26, x: 100, y: 0, toJSON: () => ({}) });
    act(() => pointer(bar, "pointerdown", 200));
    expect(q("timeline-tip")?.textContent).toBe("0:30.0");
    expect(q("timeline-position")?.textContent).toBe("0:30.0 / 2:00");
    await act(async () => pointer(bar, "pointerup", 200));
    expect(fetchMock).toHaveBeenCalledTimes(1);
    const req = sent(fetchMock, 0);
    expect(req.url).toBe("/api/player");
    expect(req.method).toBe("POST");
    expect(req.body).toEqual({ action: "seek", position_s: 30 });
    expect(req.headers).toMatchObject({ "X-Touchline": "1" });
  });

  it("shows the time under the pointer while dragging and seeks where it is released", async () => {
    const fetchMock = stubFetch(() => logPlayer());
    act(() => t.root.render(<Timeline />));
    showLog();
    const bar = q("timeline-bar") as HTMLElement;
    bar.getBoundingClientRect = () => ({ left: 0, width: 120, top: 0, height: 26, right: 120, bottom: 26, x: 0, y: 0, toJSON: () => ({}) });
    act(() => pointer(bar, "pointerdown", 10));
    act(() => pointer(bar, "pointermove", 95));
    expect(q("timeline-tip")?.textContent).toBe("1:35.0");
    await act(async () => pointer(bar, "pointerup", 200));
    const last = sent(fetchMock, fetchMock.mock.calls.length - 1);
    expect(last.body).toEqual({ action: "seek", position_s: 120 });
  });

  it("plays at the chosen speed, and pauses", async () => {
    const fetchMock = stubFetch((_u, init) => {
      const body = JSON.parse(String(init.body)) as { action: string; speed?: number };
      return logPlayer({ playing: body.action === "play", speed: body.speed ?? 1 });
    });
    act(() => t.root.render(<Timeline />));
    showLog({ playing: false, speed: 1 });
    expect(q("timeline-play")?.getAttribute("aria-label")).toBe("Play");
    // a speed chosen while paused goes out with the next play
    const select = q("timeline-speed") as HTMLSelectElement;
    act(() => {
      select.value = "0.25";
      select.dispatchEvent(new Event("change", { bubbles: true }));
    });
    expect(fetchMock).not.toHaveBeenCalled();
    await act(async () => (q("timeline-play") as HTMLButtonElement).click());
    expect(sent(fetchMock, 0).body).toEqual({ action: "play", speed: 0.25 });
    expect(q("timeline-play")?.getAttribute("aria-label")).toBe("Pause");
    expect((q("timeline-speed") as HTMLSelectElement).value).toBe("0.25");
    await act(async () => (q("timeline-play") as HTMLButtonElement).click());
    expect(sent(fetchMock, 1).body).toEqual({ action: "pause" });
    // while playing, a speed goes out at once ("max" = 0)
    showLog({ playing: true, speed: 1 });
    await act(async () => {
      const s = q("timeline-speed") as HTMLSelectElement;
      s.value = "0";
      s.dispatchEvent(new Event("change", { bubbles: true }));
    });
    expect(sent(fetchMock, 2).body).toEqual({ action: "play", speed: 0 });
  });

  it("steps frames, jumps to events and goes back to live", async () => {
    const fetchMock = stubFetch(() => logPlayer());
    act(() => t.root.render(<Timeline />));
    showLog();
    for (const id of ["timeline-step-back", "timeline-step-forward", "timeline-prev-event", "timeline-next-event", "timeline-live"]) {
      await act(async () => (q(id) as HTMLButtonElement).click());
    }
    expect(fetchMock.mock.calls.map((_c, i) => sent(fetchMock, i).body)).toEqual([
      { action: "step", frames: -1 },
      { action: "step", frames: 1 },
      { action: "jump", kind: "any", direction: "prev" },
      { action: "jump", kind: "any", direction: "next" },
      { action: "live" },
    ]);
    expect(q("timeline-step-back")?.getAttribute("aria-label")).toBe("One frame back");
  });

  it("shows the server's reason in a toast when an action is refused", async () => {
    const fn = vi.fn(async () => new Response(JSON.stringify({ detail: "no log open" }), { status: 422 }));
    vi.stubGlobal("fetch", fn);
    const toasts = await import("../store/toasts");
    const push = vi.spyOn(toasts, "pushToast");
    act(() => t.root.render(<Timeline />));
    showLog();
    await act(async () => (q("timeline-step-forward") as HTMLButtonElement).click());
    expect(push).toHaveBeenCalledWith("error", expect.stringContaining("no log open"));
    push.mockRestore();
  });
});

describe("Replay badge and logs", () => {
  it("shows a REPLAY badge with the file while replaying, none when live", () => {
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    expect(q("replay-badge")).toBeNull();
    showLog({}, replayClock({ file: "var/logs/final.log.gz" }));
    expect(q("replay-badge")?.textContent).toBe("REPLAYfinal.log.gz");
    expect(q("replay-badge")?.getAttribute("title")).toContain("commands are not sent");
  });

  it("lists the logs and opens one; shows loading, error and warning", async () => {
    const fetchMock = stubFetch((url) =>
      url === "/api/logs"
        ? { folders: ["var/logs"], files: [{ name: "a.log.gz", path: "var/logs/a.log.gz", size_bytes: 2_500_000, modified_unix: 1_700_000_000 }] }
        : logPlayer({ file: "var/logs/a.log.gz" }),
    );
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ player: player({ loading: 0.42, error: "bad record", warning: "truncated tail" }) }));
    await act(async () => (q("open-log") as HTMLButtonElement).click());
    expect(q("logs-dialog")).not.toBeNull();
    expect(sent(fetchMock, 0).url).toBe("/api/logs");
    expect(q("log-row-a.log.gz")?.textContent).toContain("2.5 MB");
    expect(q("logs-loading")?.textContent).toContain("42%");
    expect(q("logs-error")?.textContent).toBe("bad record");
    expect(q("logs-warning")?.textContent).toBe("truncated tail");
    act(() => appStore.setState({ player: player() }));
    await act(async () => (q("log-open-a.log.gz") as HTMLButtonElement).click());
    expect(sent(fetchMock, 1).body).toEqual({ action: "open", path: "var/logs/a.log.gz" });
    expect(appStore.getState().player?.source).toBe("log");
    // opened (no indexing left): the dialog gives way to the timeline
    expect(q("logs-dialog")).toBeNull();
  });

  it("keeps a player message that came while the open was out over the open's older answer", async () => {
    // a log indexed from the cache: the websocket says "open" before the POST is answered "loading"
    let answer: (v: Response) => void = () => {};
    vi.stubGlobal("fetch", vi.fn((url: string) =>
      url === "/api/logs"
        ? Promise.resolve(new Response(JSON.stringify({ folders: ["var/logs"], files: [{ name: "c.log", path: "var/logs/c.log", size_bytes: 1, modified_unix: 1 }] })))
        : new Promise<Response>((resolve) => (answer = resolve))));
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ player: player() }));
    await act(async () => (q("open-log") as HTMLButtonElement).click());
    await act(async () => (q("log-open-c.log") as HTMLButtonElement).click());
    act(() => appStore.setState({ player: logPlayer({ loading: null, epoch: 1 }) }));
    await act(async () => answer(new Response(JSON.stringify(player({ loading: 0, file: "var/logs/c.log" })))));
    expect(appStore.getState().player?.source).toBe("log");
    expect(appStore.getState().player?.loading).toBeNull();
    expect(q("logs-dialog")).toBeNull();
  });

  it("stays open while the log is indexed and closes when it is done", async () => {
    stubFetch((url) =>
      url === "/api/logs"
        ? { folders: ["var/logs"], files: [{ name: "b.log", path: "var/logs/b.log", size_bytes: 1, modified_unix: 1 }] }
        : logPlayer({ loading: 0 }),
    );
    act(() => t.root.render(<TopBar onRetryNow={() => {}} />));
    act(() => appStore.setState({ player: player() }));
    await act(async () => (q("open-log") as HTMLButtonElement).click());
    await act(async () => (q("log-open-b.log") as HTMLButtonElement).click());
    expect(q("logs-dialog")).not.toBeNull();
    expect(q("logs-loading")?.textContent).toContain("0%");
    act(() => appStore.setState({ player: logPlayer({ loading: 0.5 }) }));
    expect(q("logs-loading")?.textContent).toContain("50%");
    act(() => appStore.setState({ player: logPlayer({ loading: null }) }));
    expect(q("logs-dialog")).toBeNull();
  });
});

describe("RecordIndicator", () => {
  const withRec = (r: Parameters<typeof recording>[0]) => act(() => appStore.setState({ health: { ...health(), recording: recording(r) } }));

  it("shows REC with file, size and duration while recording", () => {
    act(() => t.root.render(<RecordIndicator />));
    withRec({ recording: true, file: "2026-11-25_0900.log.gz", size_bytes: 12_345_678, duration_s: 65 });
    const el = q("record-indicator")!;
    expect(el.getAttribute("data-state")).toBe("on");
    expect(el.textContent).toContain("REC");
    expect(el.textContent).toContain("2026-11-25_0900.log.gz");
    expect(q("record-size")?.textContent).toBe("12.3 MB");
    expect(q("record-duration")?.textContent).toBe("1:05");
  });

  it("shows rec off when disabled (no new-file button) and an error in red with its reason", () => {
    act(() => t.root.render(<RecordIndicator />));
    withRec({ enabled: false });
    expect(q("record-indicator")?.getAttribute("data-state")).toBe("off");
    expect(q("record-indicator")?.textContent).toBe("rec off");
    expect(q("record-new-file")).toBeNull();
    withRec({ recording: false });
    expect(q("record-indicator")?.getAttribute("data-state")).toBe("idle");
    expect(q("record-start")).not.toBeNull();
    withRec({ recording: false, error: "disk full" });
    expect(q("record-indicator")?.getAttribute("data-state")).toBe("error");
    expect(q("record-indicator")?.className).toContain("rec-error");
    expect(q("record-indicator")?.getAttribute("title")).toBe("disk full");
  });

  it("starts a new file", async () => {
    const fetchMock = stubFetch(() => recording({ recording: true, file: "new.log.gz" }));
    act(() => t.root.render(<RecordIndicator />));
    withRec({ recording: true, file: "old.log.gz" });
    await act(async () => (q("record-new-file") as HTMLButtonElement).click());
    expect(sent(fetchMock, 0)).toMatchObject({ url: "/api/recording", method: "POST", body: { action: "new-file" } });
    expect(q("record-indicator")?.textContent).toContain("new.log.gz");
  });
});
