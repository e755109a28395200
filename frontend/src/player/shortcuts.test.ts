// @vitest-environment jsdom
import { beforeEach, describe, expect, it, vi } from "vitest";
import { plotsStore } from "../plots/sampler";
import { appStore, initialAppState } from "../store/appStore";
import { logPlayer, player, replayClock, world } from "../ws/fixtures";

const calls: unknown[][] = [];
vi.mock("./actions", async (orig) => {
  const real = await orig<typeof import("./actions")>();
  const rec =
    (name: string) =>
    async (...args: unknown[]) => {
      calls.push([name, ...args]);
      return true;
    };
  return {
    ...real,
    togglePlay: rec("togglePlay"),
    step: rec("step"),
    seek: rec("seek"),
    changeSpeed: rec("changeSpeed"),
  };
});

const { handleKey } = await import("../shortcuts");

function key(k: string, extra: KeyboardEventInit = {}): boolean {
  return handleKey(new KeyboardEvent("keydown", { key: k, ...extra }));
}

describe("replay shortcuts", () => {
  beforeEach(() => {
    calls.length = 0;
    appStore.setState(initialAppState());
    plotsStore.setState({ paused: false });
  });

  it("keeps Space for the plots and ignores arrows and +/- when live", () => {
    appStore.setState({ player: player(), world: world(1) });
    expect(key(" ")).toBe(true);
    expect(plotsStore.getState().paused).toBe(true);
    expect(key("ArrowLeft")).toBe(false);
    expect(key("+")).toBe(false);
    expect(calls).toEqual([]);
  });

  it("plays/pauses, steps, seeks 1 s and changes speed while replaying", () => {
    appStore.setState({ player: logPlayer({ speed: 1 }), world: world(1, { replay: replayClock({ position_s: 30 }) }) });
    expect(key(" ")).toBe(true);
    expect(plotsStore.getState().paused).toBe(false);
    key("ArrowLeft");
    key("ArrowRight");
    key("ArrowRight", { shiftKey: true });
    key("ArrowLeft", { shiftKey: true });
    key("+");
    key("-");
    expect(calls).toEqual([
      ["togglePlay"],
      ["step", -1],
      ["step", 1],
      ["seek", 31],
      ["seek", 29],
      ["changeSpeed", 2],
      ["changeSpeed", 0.5],
    ]);
  });

  it("keeps the other shortcuts while replaying", () => {
    appStore.setState({ player: logPlayer(), world: world(1, { replay: replayClock() }) });
    expect(key("Escape")).toBe(true);
    expect(key("?")).toBe(true);
  });

  it("leaves a key alone that the element took already (the code editor's Escape, say)", () => {
    appStore.setState({ player: logPlayer(), world: world(1, { replay: replayClock() }) });
    const ev = new KeyboardEvent("keydown", { key: " ", cancelable: true });
    ev.preventDefault();
    expect(handleKey(ev)).toBe(false);
    expect(calls).toEqual([]);
  });
});
