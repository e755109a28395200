import { useEffect } from "react";
import { sameRobot } from "./api/types";
import { selectRobot } from "./actions";
import { FieldView } from "./components/FieldView";
import { RobotDetails } from "./components/RobotDetails";
import { RobotTable } from "./components/RobotTable";
import { Toasts } from "./components/Toasts";
import { TopBar } from "./components/TopBar";
import { useAppState, useThrottledWorld } from "./store/hooks";

export function App({ onRetryNow }: { onRetryNow: () => void }) {
  const world = useThrottledWorld(200);
  const selected = useAppState((s) => s.selected);
  const robot = selected ? (world?.robots.find((r) => sameRobot(r, selected)) ?? null) : null;

  useEffect(() => {
    const onKey = (ev: KeyboardEvent) => {
      if (ev.key !== "Escape") return;
      const el = ev.target as HTMLElement | null;
      if (el && (el.tagName === "INPUT" || el.tagName === "TEXTAREA" || el.isContentEditable)) return;
      selectRobot(null);
    };
    window.addEventListener("keydown", onKey);
    return () => window.removeEventListener("keydown", onKey);
  }, []);

  return (
    <div className="app">
      <TopBar onRetryNow={onRetryNow} />
      <main className="main">
        <div className="field-col">
          <FieldView />
          <div className="hint" data-testid="hint">
            {selected
              ? `Click a point on the field to send ${selected.team} ${selected.id} there · click another robot to switch · Esc to deselect`
              : "Click a robot, then a point to send it there"}
          </div>
        </div>
        <aside className="panel">
          <RobotDetails selected={selected} robot={robot} />
          <RobotTable robots={world?.robots ?? []} selected={selected} />
        </aside>
      </main>
      <Toasts />
    </div>
  );
}
