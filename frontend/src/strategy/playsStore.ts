// The plays of the station (GET /api/strategy, fetched once per connection and again when the
// team folder's plays change: health.team_code) and choosing one (PATCH /api/params
// {"strategy": {"play": name}}; a refusal shows the server's reason).

import { useSyncExternalStore } from "react";
import { ApiError, getStrategy } from "../api/http";
import type { AppStore } from "../store/appStore";
import type { StrategyInfo } from "../api/types";
import { commitPatch, ensureSchema } from "../params/paramsStore";
import { createStore } from "../store/createStore";
import { pushToast } from "../store/toasts";
import { PLAY_PATH, humanizePlay, robotPlayPatch, teamPlaysKey } from "./plays";

export interface PlaysState {
  info: StrategyInfo | null;
  /** Why GET /api/strategy failed (e.g. a station without strategy: 404). */
  error: string | null;
  loading: boolean;
  /** A play being sent (shown selected until the server answers). */
  pending: string | null;
}

export const playsStore = createStore<PlaysState>({ info: null, error: null, loading: false, pending: null });

/** A forced fetch asked for while one was under way: its answer may be older than the change. */
let again = false;

/** Fetch the plays unless they are loaded (or `force`). Also loads the parameter schema (fallback list). */
export async function ensurePlays(force = false): Promise<void> {
  const s = playsStore.getState();
  if (s.loading) {
    if (force) again = true;
    return;
  }
  if (s.info && !force) return;
  playsStore.setState({ loading: true });
  void ensureSchema(force);
  try {
    const info = await getStrategy();
    playsStore.setState({ info, error: null, loading: false });
  } catch (e) {
    playsStore.setState({ error: e instanceof Error ? e.message : String(e), loading: false });
  }
  if (again) {
    again = false;
    await ensurePlays(true);
  }
}

/**
 * Keeps the play lists in step with the team folder: when a health message shows team plays
 * added, removed or retitled (health.team_code), the plays and the parameter schema (whose
 * `strategy.play` choices list them) are fetched again. No page reload. Returns the unsubscribe.
 */
export function followTeamPlays(store: AppStore): () => void {
  let last: string | null = null;
  let lastFiles: unknown = undefined;
  return store.subscribe(() => {
    const files = store.getState().health?.team_code;
    if (files === lastFiles) return; // world messages: nothing to look at
    lastFiles = files;
    if (!Array.isArray(files)) return;
    const key = teamPlaysKey(files);
    const first = last === null;
    if (key === last) return;
    last = key;
    // the first sight of the folder: the fetch once per connection (PlaySelector) has it
    if (!first && playsStore.getState().info !== null) void ensurePlays(true);
  });
}

export function usePlays(): PlaysState {
  return useSyncExternalStore(playsStore.subscribe, playsStore.getState, playsStore.getState);
}

/** Choose a play. Resolves true when the station took it; a refusal is shown as a toast. */
export async function choosePlay(name: string, title = humanizePlay(name)): Promise<boolean> {
  playsStore.setState({ pending: name });
  let err: string | null;
  try {
    err = await commitPatch({ [PLAY_PATH[0]]: { [PLAY_PATH[1]]: name } });
  } catch (e) {
    err = e instanceof ApiError || e instanceof Error ? e.message : String(e);
  }
  playsStore.setState({ pending: null });
  if (err) {
    pushToast("error", `Play "${title}" refused: ${err}`);
    return false;
  }
  pushToast("info", `Play: ${title}`);
  return true;
}

/** Give robot `id` of our team its own play (null: the team's play again). Resolves to null or
 * the server's reason for refusing (also shown as a toast). */
export async function chooseRobotPlay(id: number, play: string | null): Promise<string | null> {
  let err: string | null;
  try {
    err = await commitPatch(robotPlayPatch(id, play));
  } catch (e) {
    err = e instanceof Error ? e.message : String(e);
  }
  if (err) pushToast("error", `Play for robot ${id} refused: ${err}`);
  return err;
}
