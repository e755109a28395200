import { useCallback, useEffect, useMemo, useState } from "react";
import {
  ApiError,
  cancelEvaluation,
  evaluationReportPage,
  getEvaluation,
  getEvaluationReport,
  getStrategy,
  replayEvaluationRun,
  startEvaluation,
} from "../api/http";
import type { EvaluationJob, EvaluationReport, EvaluationRun, EvaluationView } from "../api/types";
import { appStore } from "../store/appStore";
import { useAppState } from "../store/hooks";
import { pushToast } from "../store/toasts";

function errorText(e: unknown): string {
  if (e instanceof ApiError) return e.status ? `${e.message} (HTTP ${e.status})` : e.message;
  return e instanceof Error ? e.message : String(e);
}

function when(unix: number): string {
  return unix > 0 ? new Date(unix * 1000).toLocaleString() : "—";
}

/** "12/49 · 10 passed · 2 failed", the job's progress line. */
export function progressText(job: EvaluationJob): string {
  if (job.state === "idle") return "no job yet";
  const head = `${job.kind === "class" ? "class · " : ""}${job.suite}${job.play ? ` · ${job.play}` : ""}`;
  const counts = `${job.done}/${job.total} · ${job.passed} passed · ${job.failed} failed`;
  const tail = job.state === "running" ? (job.last ? ` · last: ${job.last}` : "") : ` · ${job.state}${job.error ? `: ${job.error}` : ""}`;
  return `${head}: ${counts}${tail}`;
}

function Pass({ ok }: { ok: boolean }) {
  return <span className={ok ? "eval-pass" : "eval-fail"}>{ok ? "pass" : "fail"}</span>;
}

async function replay(report: string, run: string): Promise<void> {
  try {
    const player = await replayEvaluationRun({ report, run });
    if (player && typeof player === "object" && (player.source === "live" || player.source === "log")) {
      appStore.setState({ player });
    }
  } catch (e) {
    pushToast("error", `Replay of ${run} failed: ${errorText(e)}`);
  }
}

/** A match series' report: its runs are matches, with a score and no pass or fail. */
function isMatches(report: EvaluationReport): boolean {
  return report.kind === "matches" || report.kind === "ab-matches";
}

function RunRow({ report, run, match }: { report: string; run: EvaluationRun; match: boolean }) {
  const failed = match ? run.error !== "" : !run.passed;
  return (
    <tr data-testid={`eval-run-${run.id}`} className={failed ? "eval-row-failed" : ""}>
      <td>
        {run.student ? <div className="muted">{run.student}</div> : null}
        {run.name}
        {run.detail && !match ? <div className="muted">{run.detail}</div> : null}
      </td>
      <td>
        {match ? run.detail || "no result" : (
          <>
            <Pass ok={run.passed} /> {run.score.toFixed(2)}
          </>
        )}
      </td>
      <td className="eval-checks">
        {run.error ? <div className="eval-fail">{run.error}</div> : null}
        {run.team_error ? (
          <div className="eval-fail" data-testid={`eval-team-error-${run.id}`}>
            team play: {run.team_error}
          </div>
        ) : null}
        {run.checks.map((c) => (
          <div key={c.name + c.label} title={c.detail}>
            <Pass ok={c.passed} /> {c.label}: <span className="muted">{c.detail}</span>
          </div>
        ))}
      </td>
      <td>
        {run.replay && (
          <button type="button" data-testid={`eval-replay-${run.id}`} onClick={() => void replay(report, run.id)}>
            Replay
          </button>
        )}
      </td>
    </tr>
  );
}

export function ReportView({ report }: { report: EvaluationReport }) {
  const [failedOnly, setFailedOnly] = useState(false);
  const match = isMatches(report);
  const runs = failedOnly ? report.runs.filter((r) => (match ? r.error !== "" : !r.passed)) : report.runs;
  return (
    <section className="eval-report" data-testid="eval-report">
      <h3>
        {report.title}{" "}
        <a className="muted" href={evaluationReportPage(report.name)} target="_blank" rel="noreferrer" data-testid="eval-report-page">
          page
        </a>
      </h3>
      <p className="muted">
        {report.kind} · {when(report.created_unix)} ·{" "}
        {match ? `${report.runs.length} matches` : `${report.passed}/${report.runs.length} runs passed`}
        {report.score !== null ? ` · score ${report.score.toFixed(2)}` : ""}
      </p>
      {report.verdict && (
        <p className="eval-verdict" data-testid="eval-verdict">
          {report.verdict}
        </p>
      )}
      {report.grades.length > 0 && (
        <table className="difftable eval-grades" data-testid="eval-grades">
          <thead>
            <tr>
              <th>student</th>
              <th>total</th>
              {report.exercises.map((x) => (
                <th key={x}>{x}</th>
              ))}
            </tr>
          </thead>
          <tbody>
            {report.grades.map((g) => (
              <tr key={g.student} data-testid={`eval-grade-${g.student}`}>
                <th scope="row">{g.student}</th>
                <td>
                  {g.score.toFixed(2)} <span className="muted">({g.passed}/{g.scenarios})</span>
                </td>
                {report.exercises.map((x) => {
                  const c = g.cells[x];
                  if (!c) return <td key={x}>—</td>;
                  return (
                    <td key={x} title={c.note || `${c.runs_passed}/${c.runs} runs, ${c.sim_s.toFixed(1)} s simulated`}>
                      <Pass ok={c.passed} /> {c.score.toFixed(2)}
                      {c.note && !c.passed ? <div className="muted eval-note">{c.note}</div> : null}
                      {c.run && (
                        <button
                          type="button"
                          className="eval-cell-replay"
                          onClick={() => void replay(report.name, c.run ?? "")}
                          title={`replay ${c.run}`}
                          data-testid={`eval-cell-replay-${g.student}-${x}`}
                        >
                          ▶
                        </button>
                      )}
                    </td>
                  );
                })}
              </tr>
            ))}
          </tbody>
        </table>
      )}
      <label className="eval-filter">
        <input type="checkbox" checked={failedOnly} onChange={(e) => setFailedOnly(e.target.checked)} data-testid="eval-failed-only" />{" "}
        {match ? "matches without a result only" : "failed runs only"}
      </label>
      <table className="difftable eval-runs" data-testid="eval-runs">
        <thead>
          <tr>
            <th>run</th>
            <th>result</th>
            <th>checks</th>
            <th />
          </tr>
        </thead>
        <tbody>
          {runs.map((r) => (
            <RunRow key={r.id} report={report.name} run={r} match={match} />
          ))}
        </tbody>
      </table>
    </section>
  );
}

/**
 * The Evaluate tab (docs/evaluate.md): run a scenario suite (or the class's students through
 * the exercises) on the station's play and parameters in a background process pool, follow
 * its progress (the health message's `evaluation`), read the reports and replay any run.
 */
export function EvaluatePanel() {
  const job = useAppState((s) => s.health?.evaluation ?? null);
  const [view, setView] = useState<EvaluationView | null>(null);
  const [error, setError] = useState<string | null>(null);
  const [suite, setSuite] = useState("");
  const [play, setPlay] = useState("");
  const [plays, setPlays] = useState<string[]>([]);
  const [report, setReport] = useState<EvaluationReport | null>(null);
  const [busy, setBusy] = useState(false);

  const refresh = useCallback(() => {
    getEvaluation()
      .then((v) => {
        setView(v);
        setError(null);
        setSuite((s) => s || (v.suites.find((x) => x.name === "exercises")?.name ?? v.suites[0]?.name ?? ""));
      })
      .catch((e) => setError(errorText(e)));
  }, []);

  useEffect(() => {
    refresh();
    getStrategy()
      .then((s) => setPlays(s.plays.map((p) => p.name)))
      .catch(() => setPlays([]));
  }, [refresh]);

  // a job that ended: its report is new in the list; open it
  const jobKey = job ? `${job.id}:${job.state}` : "";
  useEffect(() => {
    if (!job || job.state === "running" || job.state === "idle") return;
    refresh();
    if (job.report && job.state === "done") {
      getEvaluationReport(job.report)
        .then(setReport)
        .catch(() => undefined);
    }
  }, [jobKey]);

  const chosen = useMemo(() => view?.suites.find((s) => s.name === suite) ?? null, [view, suite]);
  const running = job?.state === "running";

  const start = async (kind: "suite" | "class") => {
    setBusy(true);
    try {
      await startEvaluation({ kind, suite, play: play || null });
    } catch (e) {
      pushToast("error", `Evaluation not started: ${errorText(e)}`);
    } finally {
      setBusy(false);
    }
  };

  const open = (name: string) => {
    getEvaluationReport(name)
      .then(setReport)
      .catch((e) => pushToast("error", `Report ${name}: ${errorText(e)}`));
  };

  return (
    <div className="evaluate" data-testid="evaluate-panel">
      {error && (
        <div className="pfield-msg" role="alert">
          {error}
        </div>
      )}
      {view && !view.available && <p className="muted">{view.reason}</p>}
      <section>
        <h3>Run a suite</h3>
        <div className="eval-form">
          <label>
            suite{" "}
            <select value={suite} onChange={(e) => setSuite(e.target.value)} data-testid="eval-suite">
              {view?.suites.map((s) => (
                <option key={s.name} value={s.name}>
                  {s.name} ({s.scenarios.reduce((n, x) => n + x.runs, 0)} runs)
                </option>
              ))}
            </select>
          </label>{" "}
          <label>
            play{" "}
            <select value={play} onChange={(e) => setPlay(e.target.value)} data-testid="eval-play">
              <option value="">each scenario&apos;s own</option>
              {plays.map((p) => (
                <option key={p} value={p}>
                  {p}
                </option>
              ))}
            </select>
          </label>{" "}
          <button type="button" disabled={busy || running || !suite || !view?.available} onClick={() => void start("suite")} data-testid="eval-start">
            Run
          </button>
          {view && view.students.length > 0 && (
            <button type="button" disabled={busy || running || !suite} onClick={() => void start("class")} data-testid="eval-class">
              Grade the class ({view.students.length})
            </button>
          )}
        </div>
        <p className="muted" data-testid="eval-where">
          {view?.cluster
            ? `Runs headless on the Dask cluster ${view.cluster}`
            : `Runs headless in ${view?.workers ?? "?"} worker process${view?.workers === 1 ? "" : "es"} beside the station`}
          , with the station&apos;s parameters; nothing is sent to robots.
        </p>
        {job && job.state !== "idle" && (
          <div className="eval-job" data-testid="eval-job" data-state={job.state}>
            <progress max={Math.max(1, job.total)} value={job.done} data-testid="eval-progress" />
            <span data-testid="eval-progress-text"> {progressText(job)}</span>{" "}
            {running && (
              <button type="button" onClick={() => void cancelEvaluation().catch((e) => pushToast("error", errorText(e)))} data-testid="eval-cancel">
                Cancel
              </button>
            )}
          </div>
        )}
        {chosen && (
          <details className="eval-statements">
            <summary>
              {chosen.scenarios.length} scenario{chosen.scenarios.length === 1 ? "" : "s"} in {chosen.name}
            </summary>
            {chosen.error && <div className="eval-fail">{chosen.error}</div>}
            {chosen.scenarios.map((s) => (
              <div key={s.name} className="eval-statement">
                <b>{s.title}</b> <span className="muted">({s.name}{s.play ? `, play ${s.play}` : ""}{s.runs > 1 ? `, ${s.runs} runs` : ""})</span>
                {s.statement && <p>{s.statement}</p>}
              </div>
            ))}
          </details>
        )}
      </section>
      <section>
        <h3>
          Reports{" "}
          <button type="button" className="eval-refresh" onClick={refresh} title="list the reports folder again (python -m evaluate writes there too)" data-testid="eval-refresh">
            Refresh
          </button>
        </h3>
        {view && view.reports.length === 0 ? (
          <p className="muted">none yet</p>
        ) : (
          <table className="difftable eval-reports" data-testid="eval-reports">
            <tbody>
              {view?.reports.map((r) => (
                <tr key={r.name} data-testid={`eval-report-${r.name}`} onClick={() => open(r.name)} className={report?.name === r.name ? "eval-selected" : ""}>
                  <td>
                    {r.title}
                    <div className="muted">{when(r.created_unix)}</div>
                  </td>
                  <td>{r.kind}</td>
                  <td>{r.kind === "matches" || r.kind === "ab-matches" ? `${r.runs} matches` : `${r.passed}/${r.runs}`}</td>
                </tr>
              ))}
            </tbody>
          </table>
        )}
      </section>
      {report && <ReportView report={report} />}
    </div>
  );
}
