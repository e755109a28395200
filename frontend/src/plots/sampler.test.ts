// @vitest-environment jsdom
import { afterEach, beforeEach, describe, expect, it } from "vitest";
import { initialAppState, type AppState } from "../store/appStore";
import { createStore } from "../store/createStore";
import { health, replayClock, world } from "../ws/fixtures";
import { plotNow, plotsStore, replayPlayhead, samples, setPaused, startSampler, visibleRange } from "./sampler";

describe("sampler while replaying", () => {
  let stop: () => void = () => {};
  const store = createStore<AppState>(initialAppState());
  beforeEach(() => {
    samples.clear();
    store.setState(initialAppState());
    plotsStore.setState({ paused: false, windowS: 10 });
    stop = startSampler(store);
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
});
