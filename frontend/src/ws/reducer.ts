// Pure handling of server -> client websocket messages (docs/api.md, "Websocket /api/ws").

import type { Geometry, Health, ParamsState, Player, World } from "../api/types";

export interface LiveData {
  world: World | null;
  geometry: Geometry | null;
  health: Health | null;
  /** Server-owned parameters: pushed on every change (null before the first snapshot). */
  params: ParamsState | null;
  /** The log player (live or a log), from the snapshot and "player" messages. */
  player: Player | null;
  /** Number of messages applied (useful to detect activity). */
  messages: number;
}

export const emptyLiveData: LiveData = { world: null, geometry: null, health: null, params: null, player: null, messages: 0 };

export type ParseResult =
  | { ok: true; msg: { type: string; [k: string]: unknown } }
  | { ok: false; error: string };

/** Parse a websocket text frame; never throws. */
export function parseMessage(data: unknown): ParseResult {
  if (typeof data !== "string") return { ok: false, error: "non-text websocket frame" };
  let value: unknown;
  try {
    value = JSON.parse(data);
  } catch (e) {
    return { ok: false, error: `invalid JSON: ${(e as Error).message}` };
  }
  if (typeof value !== "object" || value === null || Array.isArray(value)) {
    return { ok: false, error: "message is not an object" };
  }
  const type = (value as { type?: unknown }).type;
  if (typeof type !== "string") return { ok: false, error: "message has no type" };
  return { ok: true, msg: value as { type: string; [k: string]: unknown } };
}

function isObject(v: unknown): v is Record<string, unknown> {
  return typeof v === "object" && v !== null && !Array.isArray(v);
}

function asWorld(v: unknown): World | undefined {
  if (!isObject(v) || typeof v.seq !== "number" || !Array.isArray(v.robots)) return undefined;
  return v as unknown as World;
}

function asGeometry(v: unknown): Geometry | null | undefined {
  if (v === null) return null;
  if (!isObject(v) || typeof v.field_length !== "number" || typeof v.field_width !== "number") {
    return undefined;
  }
  const g = v as unknown as Geometry;
  // Tolerate a server that omits the line/arc lists.
  return {
    ...g,
    lines: Array.isArray(g.lines) ? g.lines : [],
    arcs: Array.isArray(g.arcs) ? g.arcs : [],
  };
}

function asParams(v: unknown): ParamsState | undefined {
  if (!isObject(v) || typeof v.version !== "number" || !isObject(v.values)) return undefined;
  return { version: v.version, values: v.values as ParamsState["values"] };
}

function asPlayer(v: unknown): Player | undefined {
  if (!isObject(v) || (v.source !== "live" && v.source !== "log") || typeof v.epoch !== "number") return undefined;
  const p = v as unknown as Player;
  // Tolerate a server that omits the event list.
  return Array.isArray(p.events) ? p : { ...p, events: [] };
}

/** The replay's identity: a world from another replay epoch (or live <-> log) may restart its seq. */
function replayKey(w: World): string {
  const r = w.replay;
  return r ? `log:${r.epoch}` : "live";
}

function asHealth(v: unknown): Health | undefined {
  if (!isObject(v) || !isObject(v.streams)) return undefined;
  return v as unknown as Health;
}

/**
 * Apply one parsed message. Returns the same object when nothing changed (unknown type,
 * malformed payload, or an older world than the one held).
 */
export function applyMessage(state: LiveData, msg: { type: string; [k: string]: unknown }): LiveData {
  switch (msg.type) {
    case "snapshot": {
      const world = asWorld(msg.world);
      const geometry = asGeometry(msg.geometry);
      const health = asHealth(msg.health);
      if (world === undefined) return state;
      // A snapshot starts a new session: the backend may have restarted, so its seq may be
      // lower than ours. Accept it unconditionally.
      return {
        world,
        geometry: geometry === undefined ? state.geometry : geometry,
        health: health ?? state.health,
        params: asParams(msg.params) ?? state.params,
        player: asPlayer(msg.player) ?? state.player,
        messages: state.messages + 1,
      };
    }
    case "world": {
      const world = asWorld(msg.world);
      if (world === undefined) return state;
      // Older worlds are dropped, unless the replay jumped (open, seek, back to live).
      if (state.world !== null && world.seq < state.world.seq && replayKey(world) === replayKey(state.world)) {
        return state;
      }
      return { ...state, world, messages: state.messages + 1 };
    }
    case "geometry": {
      const geometry = asGeometry(msg.geometry);
      if (geometry === undefined) return state;
      return { ...state, geometry, messages: state.messages + 1 };
    }
    case "health": {
      const health = asHealth(msg.health);
      if (health === undefined) return state;
      return { ...state, health, messages: state.messages + 1 };
    }
    case "params": {
      const params = asParams(msg);
      if (params === undefined) return state;
      // Versions only grow within a session; a restarted backend sends a snapshot first.
      if (state.params !== null && params.version < state.params.version) return state;
      return { ...state, params, messages: state.messages + 1 };
    }
    case "player": {
      const player = asPlayer(msg.player);
      if (player === undefined) return state;
      return { ...state, player, messages: state.messages + 1 };
    }
    default:
      return state;
  }
}
