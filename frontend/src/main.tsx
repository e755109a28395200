import { StrictMode } from "react";
import { createRoot } from "react-dom/client";
import { App } from "./App";
import { appStore } from "./store/appStore";
import { installTestHooks } from "./testHooks";
import { startSampler } from "./plots/sampler";
import { defaultWsUrl, startWsClient } from "./ws/client";
import "./styles.css";

const client = startWsClient({
  url: defaultWsUrl(),
  store: appStore,
  log: (m) => console.warn(m),
});

// Come back quickly when the laptop wakes up or the network returns.
window.addEventListener("online", () => client.reconnectNow());
document.addEventListener("visibilitychange", () => {
  if (document.visibilityState === "visible") client.reconnectNow();
});

startSampler(appStore);
installTestHooks();

const rootEl = document.getElementById("root");
if (!rootEl) throw new Error("#root missing");
createRoot(rootEl).render(
  <StrictMode>
    <App onRetryNow={() => client.reconnectNow()} />
  </StrictMode>,
);
