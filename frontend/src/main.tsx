import { StrictMode } from "react";
import { createRoot } from "react-dom/client";
import { App } from "./App";
import { appStore } from "./store/appStore";
import { installTestHooks } from "./testHooks";
import { startSampler } from "./plots/sampler";
import { followTeamPlays } from "./strategy/playsStore";
import { defaultWsUrl, startWsClient } from "./ws/client";
import { request } from "./api/http";
import "./styles.css";

const client = startWsClient({
  url: defaultWsUrl(),
  store: appStore,
  log: (m) => console.warn(m),
  // a refused upgrade (a station started with --view-token) is not visible to the page: ask
  // over HTTP, whose 401 says how to log in (and a station that is down just fails)
  onNeverOpened: () => {
    request("GET", "/api/health").catch(() => {});
  },
});

// Come back quickly when the laptop wakes up or the network returns.
window.addEventListener("online", () => client.reconnectNow());
document.addEventListener("visibilitychange", () => {
  if (document.visibilityState === "visible") client.reconnectNow();
});

startSampler(appStore);
followTeamPlays(appStore);
installTestHooks();

const rootEl = document.getElementById("root");
if (!rootEl) throw new Error("#root missing");
createRoot(rootEl).render(
  <StrictMode>
    <App onRetryNow={() => client.reconnectNow()} />
  </StrictMode>,
);
