import { useState, type ReactNode } from "react";
import { setArmed, setEstop } from "../actions";
import type { RefereeCommand } from "../api/types";
import { useAppState, useThrottledWorld, useTicker } from "../store/hooks";
import { fmtFixed } from "../format";
import { refereeSilentFor } from "../referee";
import { uiStore, useUi } from "../store/uiStore";
import { PlaySelector } from "./PlaySelector";
import { LogsControl, RecordIndicator, ReplayBadge } from "./PlayerBar";

interface Props {
  onRetryNow: () => void;
}

function ConnectionStatus({ onRetryNow }: Props) {
  const connection = useAppState((s) => s.connection);
  const reconnecting = connection.status === "reconnecting";
  const now = useTicker(reconnecting && connection.retryAt !== null, 250);
  let label: string;
  if (connection.status === "connected") label = "connected";
  else if (connection.status === "connecting") label = "connecting…";
  else {
    const left = connection.retryAt !== null ? Math.max(0, (connection.retryAt - now) / 1000) : null;
    label = left !== null && left > 0.05 ? `reconnecting… ${left.toFixed(1)}s` : "reconnecting…";
  }
  const title =
    connection.status === "connected"
      ? "Live data from the station"
      : `${connection.lastError ?? "Not connected"}${reconnecting ? " — click to retry now" : ""}`;
  return (
    <button
      type="button"
      className={`conn conn-${connection.status}`}
      data-testid="connection-status"
      data-state={connection.status}
      title={title}
      onClick={reconnecting ? onRetryNow : undefined}
      aria-live="polite"
    >
      <span className="dot" aria-hidden="true" />
      <span className="conn-label">{label}</span>
    </button>
  );
}

function VisionRate() {
  const health = useAppState((s) => s.health);
  const vision = health?.streams?.["vision"];
  const rate = vision?.rate_hz;
  const stale = vision === undefined || vision.last_age_s > 1 || !(rate !== undefined && rate > 0);
  return (
    <div className={`stat ${stale ? "stat-bad" : ""}`} title="Vision packets per second">
      <span className="stat-label">Vision</span>
      <span className="stat-value num" data-testid="vision-rate">
        {rate === undefined ? "—" : fmtFixed(rate, 1)} Hz
      </span>
    </div>
  );
}

function refereeClass(command: RefereeCommand): string {
  if (command === "HALT") return "ref-halt";
  if (command === "STOP") return "ref-stop";
  if (command === "NORMAL_START" || command === "FORCE_START") return "ref-run";
  return "ref-other";
}

function RefereeInfo() {
  const world = useThrottledWorld(250);
  const silentFor = useAppState((s) => refereeSilentFor(s.health));
  const ref = world?.referee ?? null;
  const command = ref && ref.source !== "none" ? ref.command : null;
  return (
    <div className={`stat referee ${silentFor !== null ? "is-silent" : ""}`} title={ref ? `Stage ${ref.stage}` : "No referee messages"}>
      <span className="stat-label">Referee</span>
      <span className={`ref-cmd ${command ? refereeClass(command) : "ref-none"}`} data-testid="referee-command">
        {command ?? "—"}
      </span>
      {ref && ref.source !== "none" && (
        <span className="score num" data-testid="score">
          <span className="score-blue">{ref.blue.score}</span>:<span className="score-yellow">{ref.yellow.score}</span>
        </span>
      )}
      {silentFor !== null && (
        <span
          className="ref-silent num"
          data-testid="referee-silent"
          title="No referee message for this long: the station keeps obeying the last command"
        >
          referee silent {silentFor} s
        </span>
      )}
    </div>
  );
}

function ViewOptions() {
  const large = useUi((s) => s.largeText);
  return (
    <div className="viewopts">
      <button
        type="button"
        className={`btn btn-small ${large ? "btn-on" : ""}`}
        aria-pressed={large}
        title="Large text for a projector (L)"
        onClick={() => uiStore.setState({ largeText: !large })}
        data-testid="large-text"
      >
        A+
      </button>
      <button type="button" className="btn btn-small" title="Keyboard shortcuts (?)" onClick={() => uiStore.setState({ help: true })} data-testid="help-button">
        ?
      </button>
    </div>
  );
}

interface ConfirmProps {
  /** the dialog's accessible name */
  label: string;
  /** data-testid prefix: ``${testId}-dialog``, ``-cancel``, ``-confirm`` */
  testId: string;
  title: string;
  cancel: string;
  confirm: string;
  onCancel: () => void;
  onConfirm: () => void;
  children: ReactNode;
}

/** A question before a step that makes robots move: the safe answer first and focused, the
 * step itself in red. */
function ConfirmDialog({ label, testId, title, cancel, confirm, onCancel, onConfirm, children }: ConfirmProps) {
  return (
    <div className="overlay" role="dialog" aria-modal="true" aria-label={label} data-testid={`${testId}-dialog`}>
      <div className="overlay-box">
        <h2>{title}</h2>
        <p>{children}</p>
        <div className="row">
          <button type="button" className="btn" data-testid={`${testId}-cancel`} autoFocus onClick={onCancel}>
            {cancel}
          </button>
          <button type="button" className="btn btn-danger" data-testid={`${testId}-confirm`} onClick={onConfirm}>
            {confirm}
          </button>
        </div>
      </div>
    </div>
  );
}

function EstopButton() {
  const estop = useAppState((s) => s.world?.estop ?? false);
  const info = useAppState((s) => s.world?.estop_info ?? null);
  const [confirming, setConfirming] = useState(false);
  // pressing is one click; releasing asks first (robots may start at once)
  const since = info && info.active && info.since > 0 ? new Date(info.since * 1000).toLocaleTimeString() : "";
  return (
    <>
      <button
        type="button"
        className={`estop ${estop ? "estop-active" : ""}`}
        data-testid="estop-button"
        data-active={estop ? "true" : "false"}
        aria-pressed={estop}
        onClick={() => (estop ? setConfirming(true) : void setEstop(true))}
        title={estop ? `Emergency stop active${since ? ` since ${since}` : ""}${info?.by ? ` (${info.by})` : ""}: click to release` : "Stop every robot now"}
      >
        {estop ? "Release" : "EMERGENCY STOP"}
      </button>
      {confirming && estop && (
        <ConfirmDialog
          label="Release the emergency stop"
          testId="estop-release"
          title="Release the emergency stop?"
          cancel="Keep stopped"
          confirm="Release"
          onCancel={() => setConfirming(false)}
          onConfirm={() => {
            setConfirming(false);
            void setEstop(false);
          }}
        >
          The robots may start moving at once, under the strategy and any operator targets.
          {since ? ` Pressed at ${since}` : ""}
          {info?.by ? ` by ${info.by}.` : since ? "." : ""}
        </ConfirmDialog>
      )}
    </>
  );
}

/** Where the relay drives real robots (or an external simulator) it sends nothing until an
 * operator arms it: ARMED (red) or disarmed (grey), arming after a confirmation, disarming in
 * one click. Nothing is shown where arming is not required (the built-in simulator). */
function ArmControl() {
  const required = useAppState((s) => s.world?.arming_required ?? false);
  const armed = useAppState((s) => s.world?.armed ?? false);
  const info = useAppState((s) => s.world?.arming ?? null);
  const team = useAppState((s) => s.world?.strategy?.our_team ?? null);
  const [confirming, setConfirming] = useState(false);
  if (!required) return null;
  const who = team ?? "our team";
  const since = info && info.since > 0 ? new Date(info.since * 1000).toLocaleTimeString() : "";
  const title = armed
    ? `ARMED${since ? ` since ${since}` : ""}${info?.by ? ` (${info.by})` : ""}: commands reach the robots. Click to disarm.`
    : `Disarmed: nothing but stops reaches the robots${info?.refusal ? ` (arming refused now: ${info.refusal})` : ""}. Click to arm.`;
  return (
    <>
      <div className={`arm ${armed ? "arm-armed" : "arm-disarmed"}`} title={title}>
        <span className="arm-state" data-testid="arm-state" data-armed={armed ? "true" : "false"} aria-live="assertive">
          {armed ? "ARMED" : "disarmed"}
        </span>
        <button
          type="button"
          className={`btn btn-small ${armed ? "" : "btn-danger"}`}
          data-testid="arm-button"
          onClick={() => (armed ? void setArmed(false) : setConfirming(true))}
        >
          {armed ? "Disarm" : "Arm…"}
        </button>
      </div>
      {confirming && !armed && (
        <ConfirmDialog
          label="Arm the robots"
          testId="arm"
          title={`Robots will move: arm ${who}?`}
          cancel="Stay disarmed"
          confirm={`Arm ${who}`}
          onCancel={() => setConfirming(false)}
          onConfirm={() => {
            setConfirming(false);
            void setArmed(true);
          }}
        >
          Commands from the strategy and any operator targets reach the real robots at once. The emergency stop disarms.
        </ConfirmDialog>
      )}
    </>
  );
}

export function TopBar({ onRetryNow }: Props) {
  return (
    <header className="topbar">
      <div className="brand">
        <span className="brand-mark" aria-hidden="true" />
        Touchline
      </div>
      <ReplayBadge />
      <ConnectionStatus onRetryNow={onRetryNow} />
      <VisionRate />
      <RefereeInfo />
      <PlaySelector variant="bar" />
      <div className="spacer" />
      <RecordIndicator />
      <LogsControl />
      <ViewOptions />
      <ArmControl />
      <EstopButton />
    </header>
  );
}
