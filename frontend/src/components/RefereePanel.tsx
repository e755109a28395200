import { useState } from "react";
import type { Card } from "../api/http";
import { giveRefereeCard, giveRefereeCommand, turnInternalRefereeOff } from "../actions";
import type { Referee, RefereeCommand, RefereeGameEvent, RefereeTeam, Robot, Team } from "../api/types";
import { fmtFixed, fmtInt } from "../format";
import { placementTarget, visibleRobots } from "../referee";
import { useThrottledWorld } from "../store/hooks";
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

/** Seconds as "12.3 s"; a negative action time is "over by". */
function fmtActionTime(s: number): string {
  return s >= 0 ? `${fmtFixed(s, 1)} s left` : `over by ${fmtFixed(-s, 1)} s`;
}

/** A team's cards: "2 yellow (41 s, 12 s) · 1 red", or "none". */
export function fmtCards(t: RefereeTeam | undefined): string {
  if (!t) return "—";
  const times = (t.yellow_card_times_s ?? []).filter((v) => v > 0);
  const parts: string[] = [];
  if (t.yellow_cards > 0) parts.push(`${t.yellow_cards} yellow${times.length ? ` (${times.map((v) => `${fmtInt(v)} s`).join(", ")})` : ""}`);
  if (t.red_cards > 0) parts.push(`${t.red_cards} red`);
  return parts.length ? parts.join(" · ") : "none";
}

const SIDES: readonly Team[] = ["blue", "yellow"];

/** Per team: robots allowed, cards, fouls, ball placement; a row only when the referee says. */
function TeamRows({ referee: ref, robots }: { referee: Referee; robots: readonly Robot[] | undefined }) {
  const team = (side: Team) => ref[side];
  const any = (f: (t: RefereeTeam) => boolean) => SIDES.some((side) => f(team(side)));
  const isNum = (v: unknown): v is number => typeof v === "number" && Number.isFinite(v);
  const rows: { key: string; label: string; cell: (side: Team) => { text: string; warn?: boolean; title?: string } }[] = [];
  if (any((t) => isNum(t.max_allowed_bots))) {
    rows.push({
      key: "robots",
      label: "robots",
      cell: (side) => {
        const max = team(side).max_allowed_bots;
        if (!isNum(max)) return { text: "—" };
        const seen = visibleRobots(robots, side);
        return seen > max
          ? { text: `${seen} / ${max} allowed`, warn: true, title: `${seen - max} robot(s) too many on the field` }
          : { text: `${seen} / ${max} allowed` };
      },
    });
  }
  rows.push({ key: "cards", label: "cards", cell: (side) => ({ text: fmtCards(team(side)) }) });
  if (any((t) => isNum(t.foul_counter))) {
    rows.push({ key: "fouls", label: "fouls", cell: (side) => ({ text: fmtInt(team(side).foul_counter) }) });
  }
  if (any((t) => t.can_place_ball === false)) {
    rows.push({
      key: "placing",
      label: "placement",
      cell: (side) => {
        const t = team(side);
        const failures = isNum(t.ball_placement_failures) ? ` (${t.ball_placement_failures} failed)` : "";
        return t.can_place_ball === false ? { text: `cannot place ball${failures}`, warn: true } : { text: "—" };
      },
    });
  }
  return (
    <table className="refteam refstate-teams" data-testid="referee-teams">
      <thead>
        <tr>
          <th />
          <th className="score-blue">{ref.blue?.name || "blue"}</th>
          <th className="score-yellow">{ref.yellow?.name || "yellow"}</th>
        </tr>
      </thead>
      <tbody>
        {rows.map((row) => (
          <tr key={row.key}>
            <td className="muted-cell">{row.label}</td>
            {SIDES.map((side) => {
              const c = row.cell(side);
              return (
                <td key={side} className={`num ${c.warn ? "warn" : ""}`} title={c.title} data-testid={`referee-${row.key}-${side}`}>
                  {c.text}
                </td>
              );
            })}
          </tr>
        ))}
      </tbody>
    </table>
  );
}

/** How many recent game events the panel lists. */
export const EVENTS_SHOWN = 5;

function GameEvents({ events }: { events: RefereeGameEvent[] }) {
  if (!events.length) return null;
  return (
    <ol className="ref-events" data-testid="referee-events">
      {events.slice(0, EVENTS_SHOWN).map((e, i) => {
        const team = e.by_team === "BLUE" ? "blue" : e.by_team === "YELLOW" ? "yellow" : null;
        return (
          <li key={e.id || i} data-testid="referee-event">
            <span className="ev-type">{pretty(e.type)}</span>
            {team && <span className={`score-${team}`}> {team}</span>}
            {e.origin.length > 0 && <span className="muted-inline"> · {e.origin.join(", ")}</span>}
          </li>
        );
      })}
    </ol>
  );
}

/** Referee state as the station acts on it (world.referee); `robots` are the world's robots. */
export function RefereeState({ ref, robots }: { ref: Referee | null; robots?: readonly Robot[] }) {
  if (!ref || ref.source === "none") return <p className="muted" data-testid="referee-state">No referee: no game controller heard and the internal referee is off.</p>;
  const placement = placementTarget(ref);
  const action = ref.current_action_time_remaining_s;
  return (
    <>
      <dl className="details-grid" data-testid="referee-state">
        <dt>source</dt>
        <dd data-testid="referee-source">
          <span className={`srcpill src-${ref.source}`}>{ref.source}</span>
        </dd>
        <dt>command</dt>
        <dd data-testid="referee-panel-command">{ref.command}</dd>
        {ref.next_command && (
          <>
            <dt>next</dt>
            <dd data-testid="referee-next">{ref.next_command}</dd>
          </>
        )}
        {ref.status_message && (
          <>
            <dt>message</dt>
            <dd className="wrap" data-testid="referee-status-message">
              {ref.status_message}
            </dd>
          </>
        )}
        {typeof action === "number" && Number.isFinite(action) && (
          <>
            <dt>action time</dt>
            <dd className={`num ${action < 0 ? "warn" : ""}`} data-testid="referee-action-time">
              {fmtActionTime(action)}
            </dd>
          </>
        )}
        <dt>stage</dt>
        <dd>{pretty(ref.stage)}</dd>
        <dt>time left</dt>
        <dd className="num">{fmtClock(ref.stage_time_left_s)}</dd>
        <dt>score</dt>
        <dd className="num">
          <span className="score-blue">{ref.blue?.name || "blue"} {ref.blue?.score ?? 0}</span> :{" "}
          <span className="score-yellow">{ref.yellow?.score ?? 0} {ref.yellow?.name || "yellow"}</span>
        </dd>
        <dt>placement</dt>
        <dd className="num" data-testid="referee-placement">
          {placement ? `${fmtInt(placement.x)}, ${fmtInt(placement.y)} mm` : "—"}
        </dd>
        <dt>age</dt>
        <dd className="num">{fmtFixed(ref.age_s, 1)} s</dd>
      </dl>
      <TeamRows referee={ref} robots={robots} />
      <GameEvents events={ref.game_events ?? []} />
    </>
  );
}

const GRID: { label: string; cmds: [RefereeCommand, RefereeCommand] | [RefereeCommand] }[] = [
  { label: "Kickoff", cmds: ["PREPARE_KICKOFF_BLUE", "PREPARE_KICKOFF_YELLOW"] },
  { label: "Free kick", cmds: ["DIRECT_FREE_BLUE", "DIRECT_FREE_YELLOW"] },
  { label: "Penalty", cmds: ["PREPARE_PENALTY_BLUE", "PREPARE_PENALTY_YELLOW"] },
  { label: "Timeout", cmds: ["TIMEOUT_BLUE", "TIMEOUT_YELLOW"] },
];

/** The internal referee's card buttons: a row per card, a button per team. */
const CARD_ROWS: { card: Card; label: string; help: string }[] = [
  { card: "yellow", label: "Yellow card", help: "one robot fewer for 120 s" },
  { card: "red", label: "Red card", help: "one robot fewer for the rest of the game" },
  { card: "clear", label: "Clear cards", help: "withdraw the team's yellow and red cards" },
];

export function RefereePanel() {
  const world = useThrottledWorld(250);
  const placing = useUi((s) => s.placing);
  // the internal referee arrives with every world message: no polling beside the websocket
  const internal = world?.internal_referee ?? null;
  const [msg, setMsg] = useState<string | null>(null);

  const foreign = internal?.foreign_source ?? null;
  const disabled = foreign !== null;
  const send = async (cmd: RefereeCommand) => {
    if (cmd.startsWith("BALL_PLACEMENT")) {
      uiStore.setState({ placing: placing === cmd ? null : cmd });
      return;
    }
    setMsg(await giveRefereeCommand(cmd));
  };
  const card = async (team: Team, kind: Card) => {
    setMsg(await giveRefereeCard(team, kind));
  };
  const cardBtn = (team: Team, row: (typeof CARD_ROWS)[number]) => (
    <button
      key={team}
      type="button"
      className={`btn refbtn refbtn-card refbtn-card-${row.card}`}
      disabled={disabled}
      title={`${row.label} for ${team}: ${row.help}`}
      aria-label={`${row.label} for ${team}`}
      data-testid={`ref-card-${row.card}-${team}`}
      onClick={() => void card(team, row.card)}
    >
      {team}
    </button>
  );
  const btn = (cmd: RefereeCommand, label = pretty(cmd), cls = "") => (
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
      <RefereeState ref={world?.referee ?? null} robots={world?.robots} />
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
          {CARD_ROWS.map((row) => (
            <tr key={row.card}>
              <td>{row.label}</td>
              {SIDES.map((side) => (
                <td key={side}>{cardBtn(side, row)}</td>
              ))}
            </tr>
          ))}
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
            void turnInternalRefereeOff().then(setMsg)
          }
        >
          Turn internal referee off
        </button>
      </div>
    </div>
  );
}
