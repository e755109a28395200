import { memo } from "react";
import type { Robot, RobotKey } from "../api/types";
import { sameRobot } from "../api/types";
import { selectRobot } from "../actions";
import { fmtFixed, fmtInt, speedMps } from "../format";
import { roleColor, roleName, roleTag } from "../strategy/roles";

/** The ball-contact cell: what the robot (or the simulator for it) reports back. */
export function ballCell(r: Robot): { text: string; state: "contact" | "free" | "no-answer" | "none"; title: string } {
  const fb = r.feedback;
  if (!fb) return { text: "", state: "none", title: "no feedback from this robot" };
  if (fb.no_answer) {
    return { text: "!", state: "no-answer", title: `no answer for ${fb.age_s === null ? "ever" : `${fmtFixed(fb.age_s, 1)} s`}` };
  }
  return fb.ball_contact
    ? { text: "◉", state: "contact", title: "ball at the dribbler" }
    : { text: "·", state: "free", title: "no ball contact" };
}

export function sortRobots(robots: readonly Robot[]): Robot[] {
  return [...robots].sort((a, b) => (a.team === b.team ? a.id - b.id : a.team === "blue" ? -1 : 1));
}

const Row = memo(function Row({ r, selected }: { r: Robot; selected: boolean }) {
  const target = r.target ? `${fmtInt(r.target.x)}, ${fmtInt(r.target.y)}` : "—";
  const ball = ballCell(r);
  return (
    <tr
      data-testid={`robot-row-${r.team}-${r.id}`}
      data-visible={r.visible ? "true" : "false"}
      data-selected={selected ? "true" : "false"}
      aria-selected={selected}
      className={`${selected ? "selected" : ""} ${r.visible ? "" : "invisible"}`}
      tabIndex={0}
      onClick={() => selectRobot({ team: r.team, id: r.id })}
      onKeyDown={(ev) => {
        if (ev.key === "Enter" || ev.key === " ") {
          ev.preventDefault();
          selectRobot({ team: r.team, id: r.id });
        }
      }}
    >
      <td className="c-team">
        <span className={`chip chip-${r.team}`} aria-hidden="true" />
        {r.team}
      </td>
      <td className="c-id num">{r.id}</td>
      <td className="c-vis" title={r.visible ? "visible" : `not seen for ${fmtFixed(r.age_s, 1)} s`}>
        {r.visible ? "●" : "○"}
      </td>
      <td className="c-num num" data-testid="robot-x">{fmtInt(r.x)}</td>
      <td className="c-num num" data-testid="robot-y">{fmtInt(r.y)}</td>
      <td className="c-num num" data-testid="robot-speed">{fmtFixed(speedMps(r.vx, r.vy), 2)}</td>
      <td className="c-role" data-testid="robot-role" data-role={r.role ?? ""} title={roleName(r.role)} style={{ color: roleColor(r.role) }}>
        {roleTag(r.role) ?? ""}
      </td>
      <td className={`c-ball ball-${ball.state}`} data-testid="robot-ball" data-contact={ball.state === "contact" ? "true" : "false"} data-state={ball.state} title={ball.title}>
        {ball.text}
      </td>
      <td className="c-target num" data-testid="robot-target" title={r.target ? `source: ${r.target.source}` : ""}>
        {target}
      </td>
    </tr>
  );
});

export function RobotTable({ robots, selected }: { robots: readonly Robot[]; selected: RobotKey | null }) {
  const sorted = sortRobots(robots);
  return (
    <div className="table-scroll">
      <table className="robots" data-testid="robot-table">
        <thead>
          <tr>
            <th className="c-team">Team</th>
            <th className="c-id">ID</th>
            <th className="c-vis" title="Visible">Vis</th>
            <th className="c-num">x mm</th>
            <th className="c-num">y mm</th>
            <th className="c-num" title="speed">m/s</th>
            <th className="c-role" title="Strategy role">Role</th>
            <th className="c-ball" title="Ball contact reported by the robot (! no answer)">Ball</th>
            <th className="c-target">Target</th>
          </tr>
        </thead>
        <tbody>
          {sorted.map((r) => (
            <Row key={`${r.team}-${r.id}`} r={r} selected={sameRobot(r, selected)} />
          ))}
          {sorted.length === 0 && (
            <tr className="empty">
              <td colSpan={9}>No robots yet</td>
            </tr>
          )}
        </tbody>
      </table>
    </div>
  );
}
