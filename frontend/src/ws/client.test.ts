import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import { createStore } from "../store/createStore";
import { initialAppState, type AppState } from "../store/appStore";
import { defaultWsUrl, startWsClient, type SocketLike } from "./client";
import { health, logPlayer, player, world } from "./fixtures";

class FakeSocket implements SocketLike {
  onopen: ((ev: unknown) => void) | null = null;
  onclose: ((ev: unknown) => void) | null = null;
  onerror: ((ev: unknown) => void) | null = null;
  onmessage: ((ev: { data: unknown }) => void) | null = null;
  closed = false;
  constructor(readonly url: string) {}
  close() {
    this.closed = true;
  }
  open() {
    this.onopen?.({});
  }
  send(msg: unknown) {
    this.onmessage?.({ data: JSON.stringify(msg) });
  }
  drop() {
    this.onclose?.({});
  }
}

function setup(staleMs = 4000, onNeverOpened?: () => void) {
  const store = createStore<AppState>(initialAppState());
  const sockets: FakeSocket[] = [];
  const client = startWsClient({
    url: "ws://station/api/ws",
    store,
    staleMs,
    onNeverOpened,
    createSocket: (url) => {
      const s = new FakeSocket(url);
      sockets.push(s);
      return s;
    },
  });
  const last = () => {
    const s = sockets[sockets.length - 1];
    if (!s) throw new Error("no socket");
    return s;
  };
  return { store, sockets, client, last };
}

describe("defaultWsUrl", () => {
  it("follows the page's protocol and host", () => {
    expect(defaultWsUrl({ protocol: "http:", host: "127.0.0.1:8000" })).toBe("ws://127.0.0.1:8000/api/ws");
    expect(defaultWsUrl({ protocol: "https:", host: "touchline.local" })).toBe("wss://touchline.local/api/ws");
  });
});

describe("startWsClient", () => {
  beforeEach(() => {
    vi.useFakeTimers();
  });
  afterEach(() => {
    vi.useRealTimers();
  });

  it("asks (onNeverOpened) only when a socket closes without opening (a refused upgrade)", () => {
    const never = vi.fn();
    const { last, client } = setup(4000, never);
    last().drop(); // refused: closed before it opened
    expect(never).toHaveBeenCalledTimes(1);
    vi.advanceTimersByTime(60_000);
    last().open();
    last().drop(); // opened, then lost: not a refusal
    expect(never).toHaveBeenCalledTimes(1);
    client.stop();
  });

  it("connects, applies messages and reports the state", () => {
    const { store, last, client } = setup();
    expect(last().url).toBe("ws://station/api/ws");
    expect(store.getState().connection.status).toBe("connecting");
    last().open();
    // Open but no data yet: not reported as connected.
    expect(store.getState().connection.status).toBe("connecting");
    last().send({ type: "snapshot", world: world(1), geometry: null, health: health(60) });
    expect(store.getState().connection.status).toBe("connected");
    last().send({ type: "world", world: world(2) });
    expect(store.getState().world?.seq).toBe(2);
    expect(store.getState().health?.streams["vision"]?.rate_hz).toBe(60);
    client.stop();
  });

  it("keeps the player of the snapshot and of every player message", () => {
    const { store, last, client } = setup();
    last().open();
    last().send({ type: "snapshot", world: world(1), geometry: null, health: health(60), player: player() });
    expect(store.getState().player?.source).toBe("live");
    last().send({ type: "player", player: logPlayer({ loading: null, epoch: 3 }) });
    expect(store.getState().player?.source).toBe("log");
    expect(store.getState().player?.epoch).toBe(3);
    last().send({ type: "player", player: player({ epoch: 4 }) });
    expect(store.getState().player?.source).toBe("live");
    client.stop();
  });

  it("ignores garbage frames without dropping the connection", () => {
    const { store, last, client } = setup();
    last().open();
    last().send({ type: "health", health: health() });
    last().onmessage?.({ data: "not json" });
    expect(store.getState().connection.status).toBe("connected");
    expect(last().closed).toBe(false);
    client.stop();
  });

  it("reconnects with 0.5, 1, 2, 4, 5 s backoff and resets after data flows", () => {
    const { store, sockets, last, client } = setup();
    last().drop();
    expect(store.getState().connection.status).toBe("reconnecting");
    const waits = [500, 1000, 2000, 4000, 5000, 5000];
    for (const wait of waits) {
      const n = sockets.length;
      vi.advanceTimersByTime(wait - 1);
      expect(sockets.length).toBe(n);
      vi.advanceTimersByTime(1);
      expect(sockets.length).toBe(n + 1);
      last().drop();
    }
    // Now one good connection with data resets the schedule.
    vi.advanceTimersByTime(5000);
    last().open();
    last().send({ type: "world", world: world(1) });
    expect(store.getState().connection).toMatchObject({ status: "connected", attempt: 0 });
    last().drop();
    const n = sockets.length;
    vi.advanceTimersByTime(500);
    expect(sockets.length).toBe(n + 1);
    client.stop();
  });

  it("treats error + close as a single failure", () => {
    const { sockets, last, client } = setup();
    const s = last();
    s.onerror?.({});
    s.onclose?.({});
    vi.advanceTimersByTime(500);
    expect(sockets.length).toBe(2);
    vi.advanceTimersByTime(5000);
    expect(sockets.length).toBe(2);
    client.stop();
  });

  it("drops a socket that opens but never sends anything", () => {
    const { store, sockets, last, client } = setup(2000);
    last().open();
    vi.advanceTimersByTime(2600);
    expect(sockets[0]?.closed).toBe(true);
    expect(store.getState().connection.status).toBe("reconnecting");
    client.stop();
  });

  it("drops a socket that went silent", () => {
    const { store, sockets, last, client } = setup(2000);
    last().open();
    vi.advanceTimersByTime(1000);
    last().send({ type: "world", world: world(1) });
    vi.advanceTimersByTime(1900);
    expect(store.getState().connection.status).toBe("connected");
    vi.advanceTimersByTime(700);
    expect(sockets[0]?.closed).toBe(true);
    expect(store.getState().connection.status).toBe("reconnecting");
    client.stop();
  });

  it("reconnectNow skips the wait, stop ends everything", () => {
    const { sockets, last, client } = setup();
    last().drop();
    vi.advanceTimersByTime(100);
    client.reconnectNow();
    expect(sockets.length).toBe(2);
    client.stop();
    expect(last().closed).toBe(true);
    vi.advanceTimersByTime(60_000);
    expect(sockets.length).toBe(2);
  });
});
