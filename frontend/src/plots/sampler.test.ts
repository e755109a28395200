// @vitest-environment jsdom
import { afterEach, beforeEach, describe, expect, it } from "vitest";
import type { PlayerHistory } from "../api/types";
import { initialAppState, type AppState } from "../store/appStore";
import { createStore } from "../store/createStore";
import { health, replayClock, world } from "../ws/fixtures";
import { plotNow, plotsStore, replayPlayhead, samples, setPaused, startSampler, visibleRange } from "./sampler";

describe("sampler while replaying", () => {
  let stop: () => void = () => {};
  const store = createStore<AppState>(initialAppState());
  /** What the backend's history answers (GET /api/player/history), per test. */
  let past: (seconds: number) => Promise<PlayerHistory> = () => new Promise(() => undefined);
  const asked: number[] = [];
  beforeEach(() => {
    samples.clear();
    store.setState(initialAppState());
    plotsStore.setState({ paused: false, windowS: 10 });
    past = () => new Promise(() => undefined); // never answers unless a test says so
    asked.length = 0;
    stop = startSampler(store, (seconds) => {
      asked.push(seconds);
      return past(seconds);
    });
  });
  afterEach(() => stop());

  const times = () => samples.time.slice();

  it("stamps world rows with the log's time and puts the plots' right edge at the playhead", () => {
    store.setState({ world: world(1, { replay: replayClock({ t_unix: 1_600_000_000, epoch: 3 }) }) });
    store.setState({ world: world(2, { replay: replayClock({ t_unix: 1_600_000_000.5, epoch: 3 }) }) });
    expect(times()).toEqual([1_600_000_000, 1_600_000_000.5]);
    expect(replayPlayhead()).toBe(1_600_000_000.5);
    expect(plotNow()).toBe(1_600_000_000.5);
    expect(visibleRange()).toEqual([1_600_000_000.5 - 10, 1_600_000_000.5]);
    expect(samples.latest("ball.x")?.t).toBe(1_600_000_000.5);
    expect(samples.has("replay.t_unix")).toBe(false);
  });

  it("starts the table again on a new epoch, so time never goes backwards", () => {
    store.setState({ world: world(1, { replay: replayClock({ t_unix: 1_600_000_100, epoch: 1 }) }) });
    store.setState({ world: world(2, { replay: replayClock({ t_unix: 1_600_000_101, epoch: 1 }) }) });
    store.setState({ world: world(3, { replay: replayClock({ t_unix: 1_600_000_020, epoch: 2 }) }) });
    expect(times()).toEqual([1_600_000_020]);
    store.setState({ world: world(4, { replay: replayClock({ t_unix: 1_600_000_021, epoch: 2 }) }) });
    expect(times()).toEqual([1_600_000_020, 1_600_000_021]);
  });

  it("fills the window with the log's past after a seek, before the rows that came since", async () => {
    const sample = (t: number, x: number) => ({
      t_unix: t,
      world: { ball: { x, y: 0, vx: 0, vy: 0 }, robots: [{ team: "blue" as const, id: 1, x, y: 0, orientation: 0, vx: 0, vy: 0, omega: 0 }] },
    });
    let answer: (h: PlayerHistory) => void = () => undefined;
    past = () => new Promise((resolve) => (answer = resolve));
    store.setState({ world: world(1, { replay: replayClock({ t_unix: 1_600_000_020, epoch: 2 }) }) });
    store.setState({ world: world(2, { replay: replayClock({ t_unix: 1_600_000_021, epoch: 2 }) }) });
    expect(asked).toEqual([10]); // once per new time line, for the plot window
    answer({ epoch: 2, samples: [sample(1_600_000_011, 5), sample(1_600_000_015, 6), sample(1_600_000_020, 7)] });
    await Promise.resolve();
    await Promise.resolve();
    // the sample at the seek's own time is already there (from the stream): not doubled
    expect(times()).toEqual([1_600_000_011, 1_600_000_015, 1_600_000_020, 1_600_000_021]);
    expect(samples.window(1_600_000_010, 1_600_000_016, ["robot.blue.1.x"]).cols[0]).toEqual([5, 6]);
  });

  it("drops a past that comes after the replay moved on to another seek", async () => {
    let answer: (h: PlayerHistory) => void = () => undefined;
    past = () => new Promise((resolve) => (answer = resolve));
    store.setState({ world: world(1, { replay: replayClock({ t_unix: 1_600_000_020, epoch: 2 }) }) });
    store.setState({ world: world(2, { replay: replayClock({ t_unix: 1_600_000_500, epoch: 3 }) }) });
    answer({ epoch: 2, samples: [{ t_unix: 1_600_000_011, world: { ball: null, robots: [] } }] });
    await Promise.resolve();
    await Promise.resolve();
    expect(times()).toEqual([1_600_000_500]);
  });

  it("starts again when a replay steps back without a new epoch", () => {
    store.setState({ world: world(1, { replay: replayClock({ t_unix: 1_600_000_100, epoch: 1 }) }) });
    store.setState({ world: world(2, { replay: replayClock({ t_unix: 1_600_000_099.98, epoch: 1 }) }) });
    expect(times()).toEqual([1_600_000_099.98]);
  });

  it("starts again when the source switches live <-> log, with the wall clock when live", () => {
    store.setState({ world: world(1) });
    const live = times()[0]!;
    expect(Math.abs(live - Date.now() / 1000)).toBeLessThan(5);
    expect(replayPlayhead()).toBeNull();
    store.setState({ world: world(2, { replay: replayClock({ t_unix: 1_600_000_000, epoch: 1 }) }) });
    expect(times()).toEqual([1_600_000_000]);
    store.setState({ world: world(3) });
    expect(times()).toHaveLength(1);
    expect(times()[0]!).toBeGreaterThan(1_700_000_000);
    expect(replayPlayhead()).toBeNull();
  });

  it("leaves out the live health rows while replaying, keeps them when live", () => {
    store.setState({ world: world(1, { replay: replayClock({ t_unix: 1_600_000_000 }) }) });
    store.setState({ health: health(55) });
    expect(samples.has("health.streams.vision.rate_hz")).toBe(false);
    expect(times()).toHaveLength(1);
    store.setState({ world: world(2) });
    store.setState({ health: health(56) });
    expect(samples.latest("health.streams.vision.rate_hz")?.v).toBe(56);
  });

  it("freezes the window at the playhead when paused, and follows a seek", () => {
    store.setState({ world: world(1, { replay: replayClock({ t_unix: 1_600_000_050, epoch: 1 }) }) });
    setPaused(true);
    expect(plotsStore.getState().pausedAt).toBe(1_600_000_050);
    store.setState({ world: world(2, { replay: replayClock({ t_unix: 1_600_000_010, epoch: 2 }) }) });
    expect(plotsStore.getState().pausedAt).toBe(1_600_000_010);
  });

  it("lists a team processor's outputs among the Plots tab's signals and samples them", () => {
    store.setState({ world: world(1, { team: { possession: { ours: 0.5 } } }) });
    store.setState({ world: world(2, { team: { possession: { ours: 0.75 } } }) });
    expect(samples.keys()).toContain("team.possession.ours");
    expect(samples.latest("team.possession.ours")?.v).toBe(0.75);
  });
});
