import type { Robot, RobotKey } from "../api/types";
import { clearTarget, selectRobot } from "../actions";
import { HealthSummary } from "./HealthSummary";
import { fmtDeg, fmtFixed, fmtHeading, fmtInt, speedMps } from "../format";

function Field({ label, value, testId }: { label: string; value: string; testId?: string }) {
  return (
    <>
      <dt>{label}</dt>
      <dd className="num" data-testid={testId}>
        {value}
      </dd>
    </>
  );
}

export function RobotDetails({ selected, robot }: { selected: RobotKey | null; robot: Robot | null }) {
  return (
    <section className="details" aria-label="Selected robot">
      <div className="details-head">
        {selected && <span className={`chip chip-${selected.team}`} aria-hidden="true" />}
        <h2 data-testid="selected-robot" data-team={selected?.team ?? ""} data-id={selected?.id ?? ""}>
          {selected ? `${selected.team} ${selected.id}` : "No robot selected"}
        </h2>
        {selected && (
          <div className="details-actions">
            <button
              type="button"
              className="btn"
              disabled={!robot?.target}
              onClick={() => void clearTarget(selected)}
              data-testid="clear-target"
              title="Send the robot back to the demo behaviour"
            >
              Clear target
            </button>
            <button type="button" className="btn" onClick={() => selectRobot(null)} title="Deselect (Esc)">
              ✕
            </button>
          </div>
        )}
      </div>
      {selected && !robot && <p className="muted">Not in the current world.</p>}
      {!selected && (
        <>
          <p className="muted">Click a robot on the field or in the table.</p>
          <HealthSummary />
        </>
      )}
      {robot && (
        <dl className="details-grid" data-testid="selected-robot-details">
          <Field label="x, y" value={`${fmtInt(robot.x)}, ${fmtInt(robot.y)} mm`} />
          <Field label="heading" value={fmtHeading(robot.orientation)} />
          <Field label="speed" value={`${fmtFixed(speedMps(robot.vx, robot.vy), 2)} m/s`} />
          <Field label="turn" value={`${fmtDeg(robot.omega)}/s`} />
          <Field
            label="seen"
            value={robot.visible ? `yes (cam ${robot.cameras.join(", ") || "—"})` : `no, ${fmtFixed(robot.age_s, 1)} s ago`}
          />
          <Field label="controlled" value={robot.controlled ? "yes" : "no"} />
          <Field
            label="target"
            value={
              robot.target
                ? `${fmtInt(robot.target.x)}, ${fmtInt(robot.target.y)} mm${
                    robot.target.orientation !== null ? ` @ ${fmtHeading(robot.target.orientation)}` : ""
                  } (${robot.target.source})`
                : "—"
            }
            testId="selected-target"
          />
          <Field
            label="command"
            value={
              robot.command
                ? `fwd ${fmtFixed(robot.command.forward_mps, 2)}  left ${fmtFixed(robot.command.left_mps, 2)} m/s  ${fmtFixed(robot.command.angular_radps, 2)} rad/s`
                : "—"
            }
          />
        </dl>
      )}
    </section>
  );
}
