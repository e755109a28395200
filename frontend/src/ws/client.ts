// Websocket client for /api/ws: applies messages to the store, exposes the connection
// state through the store, reconnects with backoff, and drops a silent socket.

import type { AppStore } from "../store/appStore";
import { backoffDelay, defaultBackoff, type BackoffOptions } from "./backoff";
import { applyMessage, parseMessage } from "./reducer";

export interface SocketLike {
  onopen: ((ev: unknown) => void) | null;
  onclose: ((ev: unknown) => void) | null;
  onerror: ((ev: unknown) => void) | null;
  onmessage: ((ev: { data: unknown }) => void) | null;
  close(): void;
}

export type SocketFactory = (url: string) => SocketLike;

export interface WsClientOptions {
  url: string;
  store: AppStore;
  createSocket?: SocketFactory;
  backoff?: BackoffOptions;
  /** Close and reconnect when no message arrived for this long while open (health comes at ~2 Hz). */
  staleMs?: number;
  now?: () => number;
  log?: (msg: string) => void;
  /** A socket closed before it ever opened: the station may be down, or refusing this browser
   * (a 401 on the upgrade, which a browser does not show): the page asks over HTTP. */
  onNeverOpened?: () => void;
}

export interface WsClient {
  stop(): void;
  /** Skip the remaining backoff wait and try now. */
  reconnectNow(): void;
}

export function defaultWsUrl(loc: { protocol: string; host: string } = location): string {
  return `${loc.protocol === "https:" ? "wss" : "ws"}://${loc.host}/api/ws`;
}

export function startWsClient(opts: WsClientOptions): WsClient {
  const store = opts.store;
  const createSocket: SocketFactory =
    opts.createSocket ?? ((url) => new WebSocket(url) as unknown as SocketLike);
  const backoff = opts.backoff ?? defaultBackoff;
  const staleMs = opts.staleMs ?? 4000;
  const now = opts.now ?? (() => Date.now());
  const log = opts.log ?? (() => {});

  let socket: SocketLike | null = null;
  let stopped = false;
  let attempt = 0;
  let retryTimer: ReturnType<typeof setTimeout> | null = null;
  let watchdog: ReturnType<typeof setInterval> | null = null;
  let lastMessageAt = 0;

  const setConnection = (patch: Partial<ReturnType<AppStore["getState"]>["connection"]>) => {
    store.setState((s) => ({ connection: { ...s.connection, ...patch } }));
  };

  const clearWatchdog = () => {
    if (watchdog !== null) clearInterval(watchdog);
    watchdog = null;
  };

  const scheduleReconnect = (reason: string) => {
    if (stopped || retryTimer !== null) return;
    const delay = backoffDelay(attempt, backoff);
    attempt += 1;
    setConnection({ status: "reconnecting", attempt, retryAt: now() + delay, lastError: reason });
    retryTimer = setTimeout(() => {
      retryTimer = null;
      connect();
    }, delay);
  };

  const connect = () => {
    if (stopped) return;
    setConnection({ status: attempt === 0 ? "connecting" : "reconnecting", retryAt: null });
    let ws: SocketLike;
    try {
      ws = createSocket(opts.url);
    } catch (e) {
      scheduleReconnect(`cannot open websocket: ${(e as Error).message}`);
      return;
    }
    socket = ws;
    let closed = false;
    let opened = false;
    const onGone = (reason: string) => {
      if (closed) return;
      closed = true;
      if (!opened) opts.onNeverOpened?.();
      clearWatchdog();
      if (socket === ws) socket = null;
      ws.onopen = ws.onclose = ws.onerror = ws.onmessage = null;
      try {
        ws.close();
      } catch {
        /* already closed */
      }
      scheduleReconnect(reason);
    };
    let gotData = false;
    ws.onopen = () => {
      if (closed) return;
      opened = true;
      // "connected" is reported with the first message (the snapshot), so that a
      // connected page always has data to show.
      lastMessageAt = now();
      setConnection({ retryAt: null });
      clearWatchdog();
      watchdog = setInterval(() => {
        if (now() - lastMessageAt > staleMs) onGone(`no data for ${Math.round(staleMs / 1000)} s`);
      }, Math.max(250, Math.floor(staleMs / 4)));
    };
    ws.onmessage = (ev) => {
      if (closed) return;
      lastMessageAt = now();
      const parsed = parseMessage(ev.data);
      if (!parsed.ok) {
        log(`ignored websocket message: ${parsed.error}`);
        return;
      }
      // A good message: the connection really works, reset the backoff.
      if (!gotData) {
        gotData = true;
        attempt = 0;
        setConnection({ status: "connected", attempt: 0, retryAt: null, lastError: null });
      }
      const prev = store.getState();
      const next = applyMessage(prev, parsed.msg);
      if (next !== prev) {
        store.setState({
          world: next.world,
          geometry: next.geometry,
          health: next.health,
          params: next.params,
          player: next.player,
          messages: next.messages,
        });
      }
    };
    ws.onerror = () => {
      // Browsers always follow an error with close; handle it there, but be safe.
      onGone("websocket error");
    };
    ws.onclose = () => onGone("connection closed");
  };

  connect();

  return {
    stop() {
      stopped = true;
      if (retryTimer !== null) clearTimeout(retryTimer);
      retryTimer = null;
      clearWatchdog();
      const ws = socket;
      socket = null;
      if (ws) {
        ws.onopen = ws.onclose = ws.onerror = ws.onmessage = null;
        ws.close();
      }
    },
    reconnectNow() {
      if (stopped || retryTimer === null) return;
      clearTimeout(retryTimer);
      retryTimer = null;
      connect();
    },
  };
}
