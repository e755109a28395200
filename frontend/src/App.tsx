import { lazy, Suspense, useEffect } from "react";
import { sameRobot } from "./api/types";
import { EvaluatePanel } from "./components/EvaluatePanel";
import { FieldView } from "./components/FieldView";
import { HealthPanel } from "./components/HealthPanel";
import { HelpOverlay } from "./components/HelpOverlay";
import { DrivingRequests, NamePrompt } from "./components/OperatorsPanel";
import { ParamsPanel } from "./components/ParamsPanel";
import { PlotsPanel } from "./components/PlotsPanel";
import { RefereePanel } from "./components/RefereePanel";
import { RobotDetails } from "./components/RobotDetails";
import { RobotTable } from "./components/RobotTable";
import { StrategyCard } from "./components/StrategyCard";
import { Toasts } from "./components/Toasts";
import { Timeline } from "./components/Timeline";
import { TopBar } from "./components/TopBar";
import { useReplaying } from "./components/PlayerBar";
import { installShortcuts } from "./shortcuts";
import { useAppState, useThrottledWorld } from "./store/hooks";
import { setTab, TABS, useUi } from "./store/uiStore";

// The Code tab (and, one step later, its editor) is loaded when first opened: the first
// screen does not carry it.
const CodePanel = lazy(() => import("./components/CodePanel"));

function RobotsTab() {
  const world = useThrottledWorld(200);
  const selected = useAppState((s) => s.selected);
  const robot = selected ? (world?.robots.find((r) => sameRobot(r, selected)) ?? null) : null;
  return (
    <>
      <StrategyCard />
      <RobotDetails selected={selected} robot={robot} />
      <RobotTable robots={world?.robots ?? []} selected={selected} />
    </>
  );
}

function Hint() {
  const selected = useAppState((s) => s.selected);
  const placing = useUi((s) => s.placing);
  const replaying = useReplaying();
  let text: string;
  if (replaying)
    text = "REPLAY: nothing is sent to robots · Space play/pause · ←/→ one frame · Shift+←/→ 1 s · +/− speed · ? for keys";
  else if (placing) text = `Click the field where the ball should be placed (${placing.replace(/_/g, " ").toLowerCase()}) · Esc to cancel`;
  else if (selected)
    text = `Click or drag (sets the heading) on the field to send ${selected.team} ${selected.id} · right-click: teleport · Esc deselects`;
  else text = "Click a robot, then a point to send it · wheel zoom, drag pans, F fits · right-click: teleport · ? for keys";
  return (
    <div className="hint" data-testid="hint">
      {text}
    </div>
  );
}

export function App({ onRetryNow }: { onRetryNow: () => void }) {
  const tab = useUi((s) => s.tab);
  const largeText = useUi((s) => s.largeText);
  const replaying = useReplaying();
  useEffect(() => installShortcuts(), []);
  useEffect(() => {
    document.documentElement.classList.toggle("large-text", largeText);
  }, [largeText]);

  return (
    <div className={`app tab-${tab}${replaying ? " replaying" : ""}`} data-replaying={replaying ? "true" : "false"}>
      <TopBar onRetryNow={onRetryNow} />
      <main className="main">
        <div className="field-col">
          <FieldView />
          <Timeline />
          <Hint />
        </div>
        <aside className="panel">
          <nav className="tabs" role="tablist" aria-label="Panels">
            {TABS.map((t) => (
              <button
                key={t.key}
                type="button"
                role="tab"
                aria-selected={tab === t.key}
                className={`tab ${tab === t.key ? "tab-active" : ""}`}
                data-testid={`tab-${t.key}`}
                onClick={() => setTab(t.key)}
              >
                {t.label}
              </button>
            ))}
          </nav>
          <div className="tab-body" role="tabpanel">
            <NamePrompt />
            {tab === "robots" && <RobotsTab />}
            {tab === "params" && <ParamsPanel />}
            {/* Plots stay mounted (hidden) so their buffers and uPlot instances survive tab switches. */}
            <div className="plots-host" hidden={tab !== "plots"}>
              <PlotsPanel visible={tab === "plots"} />
            </div>
            {tab === "referee" && <RefereePanel />}
            {tab === "health" && <HealthPanel />}
            {tab === "code" && (
              <Suspense fallback={<p className="muted code-pad">loading…</p>}>
                <CodePanel />
              </Suspense>
            )}
            {tab === "evaluate" && <EvaluatePanel />}
          </div>
        </aside>
      </main>
      <HelpOverlay />
      <Toasts />
      <DrivingRequests />
    </div>
  );
}
