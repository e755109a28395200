// Player and recorder actions: the server's answer updates the store at once (the websocket's
// "player" message confirms it); a refusal shows a toast with the server's reason.

import { ApiError, getLogs, postPlayer, postRecording } from "../api/http";
import type { LogList, Player, PlayerIn, Recording, RecordingIn } from "../api/types";
import { appStore } from "../store/appStore";
import { createStore } from "../store/createStore";
import { pushToast } from "../store/toasts";

function errorText(e: unknown): string {
  if (e instanceof ApiError) return e.status ? `${e.message} (HTTP ${e.status})` : e.message;
  return e instanceof Error ? e.message : String(e);
}

function describe(body: PlayerIn): string {
  switch (body.action) {
    case "open":
      return `Open ${body.path}`;
    case "play":
      return "Play";
    case "pause":
      return "Pause";
    case "seek":
      return "Seek";
    case "step":
      return "Step";
    case "jump":
      return "Jump to event";
    case "live":
      return "Back to live";
  }
}

/** Send one player action; resolves to true when the station took it. */
export async function playerAction(body: PlayerIn): Promise<boolean> {
  // The websocket's "player" messages are the truth; the answer only shows the action at once.
  // One that came while the request was out is newer than the answer (a log indexed from the
  // cache is open before its "open" is answered "loading"): the answer is not applied then.
  const before = appStore.getState().player;
  try {
    const player = await postPlayer(body);
    if (player && typeof player === "object" && (player.source === "live" || player.source === "log")) {
      if (appStore.getState().player === before) appStore.setState({ player });
    }
    return true;
  } catch (e) {
    pushToast("error", `${describe(body)} failed: ${errorText(e)}`);
    return false;
  }
}

export const openLog = (path: string) => playerAction({ action: "open", path });
export const play = (speed: number) => playerAction({ action: "play", speed });
export const pause = () => playerAction({ action: "pause" });
export const seek = (position_s: number) => playerAction({ action: "seek", position_s: Math.max(0, position_s) });
export const step = (frames: number) => playerAction({ action: "step", frames });
export const jump = (direction: "next" | "prev", kind: "command" | "stage" | "goal" | "card" | "operator" | "any" = "any") =>
  playerAction({ action: "jump", kind, direction });
export const backToLive = () => playerAction({ action: "live" });

/** The logs the station offers, or null (a toast says why). */
export async function listLogs(): Promise<LogList | null> {
  try {
    return await getLogs();
  } catch (e) {
    pushToast("error", `Cannot list the logs: ${errorText(e)}`);
    return null;
  }
}

/** A recorder action; resolves to the recorder's state, or null (a toast says why). */
export async function recordingAction(action: RecordingIn["action"]): Promise<Recording | null> {
  try {
    const rec = await postRecording(action);
    const health = appStore.getState().health;
    if (health && rec && typeof rec === "object" && typeof rec.recording === "boolean") {
      appStore.setState({ health: { ...health, recording: rec } });
    }
    return rec;
  } catch (e) {
    pushToast("error", `Recorder ${action}: ${errorText(e)}`);
    return null;
  }
}

// ---- speed and play/pause (shared by the timeline and the keyboard) ----

/** A speed chosen while paused: sent with the next play (the station has no separate speed action). */
export const speedStore = createStore<{ pending: number | null }>({ pending: null });

/** The speed the timeline shows: the pending one while paused, else the station's. */
export function shownSpeed(player: Player | null, pending: number | null): number {
  if (!player) return 1;
  return !player.playing && pending !== null ? pending : player.speed;
}

/** Choose a speed: applied at once while playing, kept for the next play while paused. */
export async function changeSpeed(speed: number): Promise<void> {
  const player = appStore.getState().player;
  if (player?.playing) {
    if (await play(speed)) speedStore.setState({ pending: null });
  } else speedStore.setState({ pending: speed });
}

export async function togglePlay(): Promise<void> {
  const player = appStore.getState().player;
  if (!player || player.source !== "log") return;
  if (player.playing) {
    await pause();
    return;
  }
  const speed = shownSpeed(player, speedStore.getState().pending);
  if (await play(speed)) speedStore.setState({ pending: null });
}

/** True while the station replays a log (commands are not sent then). */
export function isReplaying(): boolean {
  const s = appStore.getState();
  return s.player?.source === "log" || (s.world?.replay ?? null) !== null;
}
