import { describe, expect, it } from "vitest";
import { geometry, health, logPlayer, player, replayClock, world } from "./fixtures";
import { applyMessage, emptyLiveData, parseMessage, type LiveData } from "./reducer";

function apply(state: LiveData, msg: unknown): LiveData {
  const parsed = parseMessage(JSON.stringify(msg));
  if (!parsed.ok) throw new Error(parsed.error);
  return applyMessage(state, parsed.msg);
}

describe("parseMessage", () => {
  it("rejects non-text, invalid JSON, non-objects and missing types", () => {
    expect(parseMessage(new ArrayBuffer(2)).ok).toBe(false);
    expect(parseMessage("{nope").ok).toBe(false);
    expect(parseMessage("[1,2]").ok).toBe(false);
    expect(parseMessage("null").ok).toBe(false);
    expect(parseMessage('{"world": {}}').ok).toBe(false);
  });
  it("accepts a typed object", () => {
    const r = parseMessage('{"type":"world","world":{"seq":1}}');
    expect(r.ok && r.msg.type).toBe("world");
  });
});

describe("applyMessage", () => {
  it("takes everything from a snapshot", () => {
    const s = apply(emptyLiveData, { type: "snapshot", world: world(5), geometry, health: health(58) });
    expect(s.world?.seq).toBe(5);
    expect(s.geometry?.field_length).toBe(12000);
    expect(s.health?.streams["vision"]?.rate_hz).toBe(58);
    expect(s.messages).toBe(1);
  });

  it("keeps a null geometry from a snapshot sent before any geometry packet", () => {
    const s = apply(emptyLiveData, { type: "snapshot", world: world(1), geometry: null, health: health() });
    expect(s.geometry).toBeNull();
    expect(s.world).not.toBeNull();
  });

  it("accepts a snapshot with a lower seq (backend restarted)", () => {
    const a = apply(emptyLiveData, { type: "snapshot", world: world(900), geometry, health: health() });
    const b = apply(a, { type: "snapshot", world: world(2), geometry: null, health: health() });
    expect(b.world?.seq).toBe(2);
    expect(b.geometry).toBeNull();
  });

  it("updates the world and ignores stale ones", () => {
    let s = apply(emptyLiveData, { type: "world", world: world(10) });
    expect(s.world?.seq).toBe(10);
    s = apply(s, { type: "world", world: world(11, { estop: true }) });
    expect(s.world?.estop).toBe(true);
    const before = s;
    s = apply(s, { type: "world", world: world(9) });
    expect(s).toBe(before);
  });

  it("updates geometry and health independently of the world", () => {
    let s = apply(emptyLiveData, { type: "world", world: world(1) });
    const w = s.world;
    s = apply(s, { type: "geometry", geometry });
    s = apply(s, { type: "health", health: health(42) });
    expect(s.world).toBe(w);
    expect(s.geometry?.field_width).toBe(9000);
    expect(s.health?.streams["vision"]?.rate_hz).toBe(42);
    expect(s.messages).toBe(3);
  });

  it("fills missing line and arc lists of a geometry", () => {
    const { lines: _l, arcs: _a, ...bare } = geometry;
    const s = apply(emptyLiveData, { type: "geometry", geometry: bare });
    expect(s.geometry?.lines).toEqual([]);
    expect(s.geometry?.arcs).toEqual([]);
  });

  it("returns the same state for unknown types and malformed payloads", () => {
    const s = apply(emptyLiveData, { type: "world", world: world(3) });
    expect(apply(s, { type: "telemetry", data: 1 })).toBe(s);
    expect(apply(s, { type: "world", world: { robots: [] } })).toBe(s);
    expect(apply(s, { type: "world" })).toBe(s);
    expect(apply(s, { type: "geometry", geometry: { lines: [] } })).toBe(s);
    expect(apply(s, { type: "health", health: 3 })).toBe(s);
    expect(apply(s, { type: "snapshot", world: null, geometry: null, health: null })).toBe(s);
  });

  it("takes the player from a snapshot and keeps it when a snapshot has none", () => {
    let s = apply(emptyLiveData, { type: "snapshot", world: world(1), geometry, health: health(), player: player() });
    expect(s.player?.source).toBe("live");
    s = apply(s, { type: "snapshot", world: world(2), geometry, health: health() });
    expect(s.player?.source).toBe("live");
  });

  it("replaces the player on a player message and ignores malformed ones", () => {
    let s = apply(emptyLiveData, { type: "snapshot", world: world(1), geometry, health: health(), player: player() });
    s = apply(s, { type: "player", player: logPlayer({ playing: true }) });
    expect(s.player?.source).toBe("log");
    expect(s.player?.playing).toBe(true);
    expect(s.player?.events).toHaveLength(4);
    expect(s.messages).toBe(2);
    expect(apply(s, { type: "player", player: { source: "tape" } })).toBe(s);
    expect(apply(s, { type: "player" })).toBe(s);
    const { events: _e, ...bare } = logPlayer();
    expect(apply(s, { type: "player", player: bare }).player?.events).toEqual([]);
  });

  it("accepts a lower world seq when the replay jumped, not within one replay", () => {
    let s = apply(emptyLiveData, { type: "world", world: world(100, { replay: replayClock({ epoch: 1 }) }) });
    const before = s;
    expect(apply(s, { type: "world", world: world(50, { replay: replayClock({ epoch: 1 }) }) })).toBe(before);
    s = apply(s, { type: "world", world: world(50, { replay: replayClock({ epoch: 2 }) }) });
    expect(s.world?.seq).toBe(50);
    expect(s.world?.replay?.epoch).toBe(2);
    s = apply(s, { type: "world", world: world(10) });
    expect(s.world?.replay).toBeNull();
  });
});
