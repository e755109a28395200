// The selected robot's controller and filter: per-robot choices (PATCH /api/params overrides),
// the effective values the world reports, the controller telemetry as rows, and one-click plots.

import { useState } from "react";
import type { Robot, RobotKey } from "../api/types";
import { fmtFixed, fmtInt } from "../format";
import { commitPatch } from "../params/paramsStore";
import { addPlot } from "../plots/sampler";
import {
  ALGORITHMS,
  FILTERS,
  controllerPatch,
  controllerPlots,
  filterPatch,
  filterPlots,
  labelOf,
  robotOverrides,
} from "../robotOverrides";
import { useAppState } from "../store/hooks";
import { pushToast } from "../store/toasts";
import { setTab } from "../store/uiStore";
import { RobotPlayChoice } from "./RobotPlayChoice";
import { Row } from "./Row";


function openPlots(plots: string[][]): void {
  for (const keys of plots) addPlot(keys);
  setTab("plots");
}

export function RobotControlPanel({ robotKey, robot }: { robotKey: RobotKey; robot: Robot }) {
  const values = useAppState((s) => s.params?.values);
  const [busy, setBusy] = useState(false);
  const [error, setError] = useState<string | null>(null);
  const ov = robotOverrides(values, robotKey);

  async function patch(body: Record<string, unknown>): Promise<void> {
    setBusy(true);
    setError(null);
    const err = await commitPatch(body);
    setBusy(false);
    if (err) {
      setError(err);
      pushToast("error", err);
    }
  }

  const ctl = robot.control ?? null;
  const effAlgorithm = ctl?.algorithm ?? null;
  const effFilter = robot.filter ?? null;

  return (
    <div className="robot-control" data-testid="robot-control">
      <RobotPlayChoice robotKey={robotKey} />
      <div className="robot-choice">
        <label>
          <span>Controller</span>
          <select
            data-testid="robot-controller-select"
            value={ov.algorithm ?? ""}
            disabled={busy || !values}
            onChange={(ev) => void patch(controllerPatch(values, robotKey, ev.target.value || null))}
          >
            <option value="">Default ({labelOf(ALGORITHMS, ov.defaultAlgorithm)})</option>
            {ALGORITHMS.map((a) => (
              <option key={a.value} value={a.value}>
                {a.label}
              </option>
            ))}
          </select>
        </label>
        <span
          className={`choice-state ${ov.algorithm ? "override" : ""}`}
          data-testid="robot-controller-effective"
          data-value={effAlgorithm ?? ""}
          data-override={ov.algorithm ? "true" : "false"}
          title={ov.algorithm ? "per-robot override" : "the station default"}
        >
          {effAlgorithm ? labelOf(ALGORITHMS, effAlgorithm) : robot.controlled ? "—" : "not controlled"}
          {ov.algorithm ? " · override" : " · default"}
        </span>
      </div>
      <div className="robot-choice">
        <label>
          <span>Filter</span>
          <select
            data-testid="robot-filter-select"
            value={ov.filter ?? ""}
            disabled={busy || !values}
            onChange={(ev) => void patch(filterPatch(robotKey, ev.target.value || null))}
          >
            <option value="">Default ({labelOf(FILTERS, ov.defaultFilter)})</option>
            {FILTERS.map((f) => (
              <option key={f.value} value={f.value}>
                {f.label}
              </option>
            ))}
          </select>
        </label>
        <span
          className={`choice-state ${ov.filter ? "override" : ""}`}
          data-testid="robot-filter-effective"
          data-value={effFilter ?? ""}
          data-override={ov.filter ? "true" : "false"}
        >
          {effFilter ? labelOf(FILTERS, effFilter) : "—"}
          {ov.filter ? " · override" : " · default"}
        </span>
      </div>
      {error && (
        <div className="pfield-msg" role="alert" data-testid="robot-choice-error">
          {error}
        </div>
      )}
      <dl className="details-grid" data-testid="robot-controller">
        <Row label="algorithm" value={effAlgorithm ? labelOf(ALGORITHMS, effAlgorithm) : "—"} testId="robot-algorithm" />
        <Row label="phase" value={ctl?.phase || "—"} testId="robot-phase" />
        <Row label="estimated C" value={ctl ? fmtFixed(ctl.c_estimate, 3) : "—"} testId="robot-c-estimate" />
        <Row
          label="x* / x"
          value={ctl ? `${ctl.has_reference ? fmtFixed(ctl.ref_x_m, 3) : "—"} / ${fmtFixed(ctl.x_m, 3)} m` : "—"}
          testId="robot-ref-x"
        />
        <Row label="path" value={ctl ? `${fmtFixed(ctl.path_length_m, 3)} m, lateral ${fmtFixed(ctl.lateral_m, 3)} m` : "—"} />
        <Row
          label="speed cmd / meas"
          value={ctl ? `${fmtFixed(ctl.cmd_speed_mps, 2)} / ${fmtFixed(ctl.meas_speed_mps, 2)} m/s` : "—"}
          testId="robot-speeds"
        />
        <Row label="heading err" value={ctl ? `${fmtFixed(ctl.heading_error_rad, 3)} rad` : "—"} />
        <Row label="restarts" value={ctl ? fmtInt(ctl.restarts) : "—"} />
        <Row
          label="raw x, y"
          value={robot.raw_x != null && robot.raw_y != null ? `${fmtInt(robot.raw_x)}, ${fmtInt(robot.raw_y)} mm` : "—"}
          testId="robot-raw-xy"
        />
        <Row label="state" value={robot.lost ? "lost" : robot.predicted ? "predicted" : robot.visible ? "measured" : "not seen"} testId="robot-track-state" />
      </dl>
      <div className="details-actions robot-plot-buttons">
        <button type="button" className="btn btn-small" data-testid="robot-plot-controller" onClick={() => openPlots(controllerPlots(robotKey))}>
          Plot C, x*/x and speeds
        </button>
        <button type="button" className="btn btn-small" data-testid="robot-plot-filter" onClick={() => openPlots(filterPlots(robotKey))}>
          Plot raw vs filtered x/y
        </button>
      </div>
    </div>
  );
}
