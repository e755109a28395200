// The application's single live store: the latest data from the websocket, the
// connection state and the selected robot. Updated outside React (websocket client,
// canvas clicks); read by the canvas every animation frame and by React via hooks.

import type { RobotKey } from "../api/types";
import { emptyLiveData, type LiveData } from "../ws/reducer";
import { createStore, type Store } from "./createStore";

export type ConnectionStatus = "connecting" | "connected" | "reconnecting";

export interface ConnectionState {
  status: ConnectionStatus;
  /** Failed attempts in a row since the last good connection. */
  attempt: number;
  /** Epoch ms of the next reconnect attempt while reconnecting. */
  retryAt: number | null;
  lastError: string | null;
}

export interface AppState extends LiveData {
  connection: ConnectionState;
  selected: RobotKey | null;
}

export function initialAppState(): AppState {
  return {
    ...emptyLiveData,
    connection: { status: "connecting", attempt: 0, retryAt: null, lastError: null },
    selected: null,
  };
}

export type AppStore = Store<AppState>;

export const appStore: AppStore = createStore<AppState>(initialAppState());
