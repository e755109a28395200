// The plays of the station (GET /api/strategy, fetched once per connection) and choosing one
// (PATCH /api/params {"strategy": {"play": name}}; a refusal shows the server's reason).

import { useSyncExternalStore } from "react";
import { ApiError, getStrategy } from "../api/http";
import type { StrategyInfo } from "../api/types";
import { commitPatch, ensureSchema } from "../params/paramsStore";
import { createStore } from "../store/createStore";
import { pushToast } from "../store/toasts";
import { PLAY_PATH, humanizePlay } from "./plays";

export interface PlaysState {
  info: StrategyInfo | null;
  /** Why GET /api/strategy failed (e.g. a station without strategy: 404). */
  error: string | null;
  loading: boolean;
  /** A play being sent (shown selected until the server answers). */
  pending: string | null;
}

export const playsStore = createStore<PlaysState>({ info: null, error: null, loading: false, pending: null });

/** Fetch the plays unless they are loaded (or `force`). Also loads the parameter schema (fallback list). */
export async function ensurePlays(force = false): Promise<void> {
  const s = playsStore.getState();
  if (s.loading || (s.info && !force)) return;
  playsStore.setState({ loading: true });
  void ensureSchema();
  try {
    const info = await getStrategy();
    playsStore.setState({ info, error: null, loading: false });
  } catch (e) {
    playsStore.setState({ error: e instanceof Error ? e.message : String(e), loading: false });
  }
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
