import type { Robot, RobotKey } from "../api/types";
import { clearTarget, selectRobot } from "../actions";
import { HealthSummary } from "./HealthSummary";
import { ParamField } from "./ParamField";
import { RobotControlPanel } from "./RobotControlPanel";
import { Row } from "./Row";
import { useParamForm } from "../params/paramsStore";
import { chooserFields, getAt } from "../params/schema";
import { useAppState } from "../store/hooks";
import { fmtDeg, fmtFixed, fmtHeading, fmtInt, speedMps } from "../format";
import { pathLengthMm, pathPoints } from "../field/paths";
import { roleName, roleTag } from "../strategy/roles";


const KNOWN = new Set([
  "team", "id", "x", "y", "orientation", "vx", "vy", "omega", "visible", "age_s", "cameras", "target", "controlled", "command",
  // shown by RobotControlPanel
  "raw_x", "raw_y", "raw_orientation", "predicted", "lost", "filter", "control",
  // shown by StrategyFields
  "role", "path", "kick", "dribbler",
  // shown by FeedbackFields
  "feedback",
]);

/** What the robot reports back: "yes" / "0.02 s ago" / "no answer for 0.8 s", round trip, losses, ... */
export function feedbackTexts(robot: Robot): {
  contact: string;
  answer: string;
  roundTrip: string;
  loss: string;
  kick: string;
  battery: string;
  kicker: string;
} | null {
  const fb = robot.feedback;
  if (!fb) return null;
  const age = fb.age_s === null ? null : `${fmtFixed(fb.age_s, 2)} s`;
  return {
    contact: fb.no_answer ? "unknown (no answer)" : fb.ball_contact ? "yes" : "no",
    answer: fb.no_answer ? `no answer ${age === null ? "yet" : `for ${age}`}` : age === null ? "—" : `${age} ago (${fb.transport})`,
    roundTrip: fb.round_trip_ms === null ? "—" : `${fmtFixed(fb.round_trip_ms, 1)} ms`,
    loss:
      fb.loss === null || fb.commands_sent === null || fb.answers === null
        ? "—"
        : `${fmtInt(fb.loss * 100)} % (${fb.answers} of ${fb.commands_sent} answered, 2 s)`,
    kick: fb.last_kick === null ? "—" : `${fb.last_kick} ${fb.last_kick_age_s === null ? "" : `${fmtFixed(fb.last_kick_age_s, 1)} s ago`}`.trim(),
    battery: fb.battery_v === null ? "—" : `${fmtFixed(fb.battery_v, 1)} V`,
    kicker: fb.kicker_v === null ? "—" : `${fmtFixed(fb.kicker_v, 0)} V`,
  };
}

/** Ball contact, answer age / "no answer", round trip, losses, last kick; voltages when reported. */
function FeedbackFields({ robot }: { robot: Robot }) {
  const f = feedbackTexts(robot);
  if (!f) return <Row label="feedback" value="—" testId="robot-feedback" />;
  return (
    <>
      <Row label="ball contact" value={f.contact} testId="robot-ball-contact" />
      <Row label="answer" value={f.answer} testId="robot-feedback" />
      {f.roundTrip !== "—" && <Row label="round trip" value={f.roundTrip} testId="robot-round-trip" />}
      {f.loss !== "—" && <Row label="losses" value={f.loss} testId="robot-loss" />}
      {f.kick !== "—" && <Row label="last kick" value={f.kick} testId="robot-last-kick" />}
      {f.battery !== "—" && <Row label="battery" value={f.battery} testId="robot-battery" />}
      {f.kicker !== "—" && <Row label="kicker charge" value={f.kicker} testId="robot-kicker-charge" />}
    </>
  );
}

/** "Goalkeeper (GK)", "3 waypoints · 2.41 m", "armed 4.0 m/s chip". */
export function strategyTexts(robot: Robot): { role: string; path: string; kick: string; dribbler: string } {
  const tag = roleTag(robot.role);
  const pts = pathPoints(robot.path);
  return {
    role: tag ? `${roleName(robot.role)} (${tag})` : "—",
    path: pts
      ? `${pts.length} waypoint${pts.length === 1 ? "" : "s"} · ${fmtFixed(pathLengthMm(robot, pts) / 1000, 2)} m`
      : "—",
    kick: robot.kick ? `armed ${fmtFixed(robot.kick.speed_mps, 1)} m/s ${robot.kick.chip ? "chip" : "flat"}` : "not armed",
    dribbler: robot.dribbler ? "on" : "off",
  };
}

/** Role, planned path, kicker and dribbler. */
function StrategyFields({ robot }: { robot: Robot }) {
  const t = strategyTexts(robot);
  return (
    <>
      <Row label="role" value={t.role} testId="robot-role-detail" />
      <Row label="path" value={t.path} testId="robot-path" />
      <Row label="kicker" value={t.kick} testId="robot-kick" />
      <Row label="dribbler" value={t.dribbler} testId="robot-dribbler" />
    </>
  );
}

function fmtAny(v: unknown): string {
  if (typeof v === "number") return Number.isInteger(v) ? String(v) : Math.abs(v) >= 100 ? fmtInt(v) : fmtFixed(v, 3);
  if (typeof v === "boolean") return v ? "yes" : "no";
  if (v === null || v === undefined) return "—";
  if (typeof v === "string") return v;
  if (Array.isArray(v)) return v.map(fmtAny).join(", ");
  return Object.entries(v as Record<string, unknown>)
    .map(([k, x]) => `${k} ${fmtAny(x)}`)
    .join("  ");
}

/** Fields the backend adds to robots later (raw_x, filter, controller, estimated C, ...), shown as they come. */
function ExtraFields({ robot }: { robot: Robot }) {
  const extra = Object.entries(robot as unknown as Record<string, unknown>).filter(([k]) => !KNOWN.has(k));
  if (extra.length === 0) return null;
  return (
    <>
      {extra.map(([k, v]) => (
        <Row key={k} label={k.replace(/_/g, " ")} value={fmtAny(v)} testId={`robot-extra-${k}`} />
      ))}
    </>
  );
}

/** Filter / controller choices from the parameter schema (any enum whose path names one). */
function Choosers() {
  const form = useParamForm();
  const values = useAppState((s) => s.params?.values);
  if (!form.groups || !values) return null;
  const fields = chooserFields(form.groups);
  if (fields.length === 0) return null;
  return (
    <div className="choosers">
      <h3 className="choosers-title">Station defaults (all robots)</h3>
      {fields.map((f) => (
        <ParamField key={f.id} f={f} value={getAt(values, f.path)} compact />
      ))}
    </div>
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
          <Row label="x, y" value={`${fmtInt(robot.x)}, ${fmtInt(robot.y)} mm`} />
          <Row label="heading" value={fmtHeading(robot.orientation)} />
          <Row label="speed" value={`${fmtFixed(speedMps(robot.vx, robot.vy), 2)} m/s`} />
          <Row label="turn" value={`${fmtDeg(robot.omega)}/s`} />
          <Row
            label="seen"
            value={robot.visible ? `yes (cam ${robot.cameras.join(", ") || "—"})` : `no, ${fmtFixed(robot.age_s, 1)} s ago`}
          />
          <Row label="controlled" value={robot.controlled ? "yes" : "no"} />
          <StrategyFields robot={robot} />
          <FeedbackFields robot={robot} />
          <Row
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
          <ExtraFields robot={robot} />
          <Row
            label="command"
            value={
              robot.command
                ? `fwd ${fmtFixed(robot.command.forward_mps, 2)}  left ${fmtFixed(robot.command.left_mps, 2)} m/s  ${fmtFixed(robot.command.angular_radps, 2)} rad/s`
                : "—"
            }
          />
        </dl>
      )}
      {robot && selected && <RobotControlPanel robotKey={selected} robot={robot} />}
      {robot && <Choosers />}
    </section>
  );
}
