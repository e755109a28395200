import { useCallback, useEffect, useState } from "react";
import { ApiError, getReferee, postRefereeCommand, postRefereeEnabled, type InternalReferee } from "../api/http";
import type { Referee } from "../api/types";
import { fmtFixed, fmtInt } from "../format";
import { useThrottledWorld } from "../store/hooks";
import { pushToast } from "../store/toasts";
import { uiStore, useUi } from "../store/uiStore";

export function fmtClock(s: number | null | undefined): string {
  if (s === null || s === undefined || !Number.isFinite(s)) return "—";
  const neg = s < 0;
  const a = Math.abs(Math.round(s));
  return `${neg ? "-" : ""}${Math.floor(a / 60)}:${String(a % 60).padStart(2, "0")}`;
}

function pretty(cmd: string): string {
  return cmd.replace(/_/g, " ").toLowerCase();
}

/** Referee state as the station acts on it (world.referee). */
export function RefereeState({ ref }: { ref: Referee | null }) {
  if (!ref || ref.source === "none") return <p className="muted" data-testid="referee-state">No referee: no game controller heard and the internal referee is off.</p>;
  return (
    <dl className="details-grid" data-testid="referee-state">
      <dt>source</dt>
      <dd data-testid="referee-source">
        <span className={`srcpill src-${ref.source}`}>{ref.source}</span>
      </dd>
      <dt>command</dt>
      <dd data-testid="referee-panel-command">{ref.command}</dd>
      <dt>stage</dt>
      <dd>{pretty(ref.stage)}</dd>
      <dt>time left</dt>
      <dd className="num">{fmtClock(ref.stage_time_left_s)}</dd>
      <dt>score</dt>
      <dd className="num">
        <span className="score-blue">{ref.blue?.name || "blue"} {ref.blue?.score ?? 0}</span> :{" "}
        <span className="score-yellow">{ref.yellow?.score ?? 0} {ref.yellow?.name || "yellow"}</span>
      </dd>
      <dt>yellow cards</dt>
      <dd className="num">
        blue {ref.blue?.yellow_cards ?? 0} · yellow {ref.yellow?.yellow_cards ?? 0}
      </dd>
      <dt>placement</dt>
      <dd className="num">{ref.designated_position ? `${fmtInt(ref.designated_position.x)}, ${fmtInt(ref.designated_position.y)} mm` : "—"}</dd>
      <dt>age</dt>
      <dd className="num">{fmtFixed(ref.age_s, 1)} s</dd>
    </dl>
  );
}

const GRID: { label: string; cmds: [string, string] | [string] }[] = [
  { label: "Kickoff", cmds: ["PREPARE_KICKOFF_BLUE", "PREPARE_KICKOFF_YELLOW"] },
  { label: "Free kick", cmds: ["DIRECT_FREE_BLUE", "DIRECT_FREE_YELLOW"] },
  { label: "Penalty", cmds: ["PREPARE_PENALTY_BLUE", "PREPARE_PENALTY_YELLOW"] },
  { label: "Timeout", cmds: ["TIMEOUT_BLUE", "TIMEOUT_YELLOW"] },
];

/** Give a command to the internal referee; resolves to an error text or null. */
export async function giveRefereeCommand(command: string, at?: { x: number; y: number }): Promise<string | null> {
  try {
    await postRefereeCommand(command, at);
    return null;
  } catch (e) {
    const msg = e instanceof ApiError ? `${e.message} (HTTP ${e.status})` : (e as Error).message;
    pushToast("error", `Referee ${command}: ${msg}`);
    return msg;
  }
}

export function RefereePanel() {
  const world = useThrottledWorld(250);
  const placing = useUi((s) => s.placing);
  const [internal, setInternal] = useState<InternalReferee | null>(null);
  const [msg, setMsg] = useState<string | null>(null);

  const refresh = useCallback(() => {
    getReferee()
      .then((r) => setInternal(r.internal))
      .catch((e) => setMsg((e as Error).message));
  }, []);
  useEffect(() => {
    refresh();
    const t = setInterval(refresh, 1000);
    return () => clearInterval(t);
  }, [refresh]);

  const foreign = internal?.foreign_source ?? null;
  const disabled = foreign !== null;
  const send = async (cmd: string) => {
    if (cmd.startsWith("BALL_PLACEMENT")) {
      uiStore.setState({ placing: placing === cmd ? null : cmd });
      return;
    }
    const err = await giveRefereeCommand(cmd);
    setMsg(err);
    refresh();
  };
  const btn = (cmd: string, label = pretty(cmd), cls = "") => (
    <button
      key={cmd}
      type="button"
      className={`btn refbtn ${cls} ${internal?.enabled && internal.command === cmd ? "refbtn-on" : ""} ${placing === cmd ? "refbtn-on" : ""}`}
      disabled={disabled}
      data-testid={`ref-${cmd}`}
      onClick={() => void send(cmd)}
    >
      {label}
    </button>
  );

  return (
    <div className="referee-panel" data-testid="referee-panel">
      <h3>Game state</h3>
      <RefereeState ref={world?.referee ?? null} />
      <h3>
        Internal referee{" "}
        <span className="muted" data-testid="internal-ref-status">
          {internal ? (internal.enabled ? `on · ${internal.command}` : "off") : "…"}
        </span>
      </h3>
      {disabled && (
        <p className="notice" data-testid="internal-ref-disabled">
          A game controller is active ({foreign}): it has the say, the internal referee stays off.
        </p>
      )}
      {internal?.disabled_reason && !disabled && <p className="muted">{internal.disabled_reason}</p>}
      <div className="refgrid">
        {btn("HALT", "HALT", "refbtn-halt")}
        {btn("STOP", "STOP", "refbtn-stop")}
        {btn("FORCE_START", "FORCE START", "refbtn-go")}
        {btn("NORMAL_START", "NORMAL START", "refbtn-go")}
      </div>
      <table className="refteam">
        <thead>
          <tr>
            <th />
            <th className="score-blue">blue</th>
            <th className="score-yellow">yellow</th>
          </tr>
        </thead>
        <tbody>
          {GRID.map((row) => (
            <tr key={row.label}>
              <td>{row.label}</td>
              {row.cmds.map((c) => (
                <td key={c}>{btn(c, c.endsWith("BLUE") ? "blue" : "yellow")}</td>
              ))}
            </tr>
          ))}
          <tr>
            <td>Ball placement</td>
            <td>{btn("BALL_PLACEMENT_BLUE", "blue…")}</td>
            <td>{btn("BALL_PLACEMENT_YELLOW", "yellow…")}</td>
          </tr>
        </tbody>
      </table>
      {placing && (
        <p className="notice" data-testid="placement-hint">
          Click the field where the ball should go ({pretty(placing)}). Esc cancels.
        </p>
      )}
      {msg && (
        <div className="pfield-msg" role="alert" data-testid="referee-error">
          {msg}
        </div>
      )}
      <div className="row">
        <button
          type="button"
          className="btn btn-small"
          disabled={disabled || !internal?.enabled}
          data-testid="internal-ref-off"
          onClick={() =>
            void postRefereeEnabled(false)
              .then(() => {
                setMsg(null);
                refresh();
              })
              .catch((e) => setMsg((e as Error).message))
          }
        >
          Turn internal referee off
        </button>
      </div>
    </div>
  );
}
