// @vitest-environment jsdom
import { act } from "react";
import { afterEach, describe, expect, it, vi } from "vitest";
import type { EvaluationReport } from "../api/types";
import { appStore, initialAppState } from "../store/appStore";
import { domPerTest } from "../testing/dom";
import { evaluationJob } from "../ws/fixtures";
import { progressText, ReportView } from "./EvaluatePanel";

(globalThis as { IS_REACT_ACT_ENVIRONMENT?: boolean }).IS_REACT_ACT_ENVIRONMENT = true;

const t = domPerTest(() => appStore.setState(initialAppState()));
const q = t.q;

afterEach(() => vi.unstubAllGlobals());

const CLASS_REPORT: EvaluationReport = {
  name: "20250101-120000-class-exercises",
  title: "class c1: exercises",
  kind: "class",
  created_unix: 1735732800,
  passed: 1,
  score: 0.5,
  verdict: "",
  exercises: ["drive_to_point_1", "goalkeeper"],
  grades: [
    {
      student: "ada",
      score: 0.5,
      passed: 1,
      scenarios: 2,
      cells: {
        drive_to_point_1: { passed: true, score: 1, runs: 1, runs_passed: 1, sim_s: 8, note: "", run: null },
        goalkeeper: { passed: false, score: 0, runs: 2, runs_passed: 0, sim_s: 7, note: "0/2 runs", run: "ada.goalkeeper#1" },
      },
    },
  ],
  runs: [
    {
      id: "ada.goalkeeper#1",
      name: "goalkeeper#1",
      scenario: "goalkeeper",
      title: "Goalkeeper",
      student: "ada",
      seed: 100,
      passed: false,
      score: 0,
      detail: "",
      error: "",
      team_error: "",
      sim_s: 3.5,
      replay: true,
      checks: [{ name: "keeper_saved", label: "saved", passed: false, score: 0, detail: "conceded at 0.93 s" }],
    },
  ],
  timing: {},
};

describe("Evaluate", () => {
  it("says a job's progress in one line", () => {
    expect(progressText(evaluationJob())).toBe("no job yet");
    expect(progressText(evaluationJob({ state: "running", suite: "exercises", done: 3, total: 49, passed: 2, failed: 1, last: "pass_1: failed" }))).toBe(
      "exercises: 3/49 · 2 passed · 1 failed · last: pass_1: failed",
    );
    expect(progressText(evaluationJob({ state: "failed", kind: "class", suite: "exercises", error: "boom" }))).toContain("class · exercises: 0/0");
  });

  it("shows the grade table and replays a failed run by its names", async () => {
    const fetchMock = vi.fn(async () => new Response(JSON.stringify({ source: "log" })));
    vi.stubGlobal("fetch", fetchMock);
    await act(async () => t.root.render(<ReportView report={CLASS_REPORT} />));
    const row = q("eval-grade-ada")!;
    expect(row.textContent).toContain("0.50");
    expect(row.querySelectorAll(".eval-pass").length).toBe(1);
    expect(row.querySelectorAll(".eval-fail").length).toBe(1);
    expect(q("eval-run-ada.goalkeeper#1")!.textContent).toContain("conceded at 0.93 s");
    await act(async () => q("eval-replay-ada.goalkeeper#1")!.dispatchEvent(new MouseEvent("click", { bubbles: true })));
    const [url, init] = fetchMock.mock.calls[0] as unknown as [string, RequestInit];
    expect(url).toBe("/api/evaluate/replay");
    expect(JSON.parse(String(init.body))).toEqual({ report: CLASS_REPORT.name, run: "ada.goalkeeper#1" });
  });

  it("shows a match series as matches with their scores and the verdict, not as failed runs", async () => {
    const match = (n: number, detail: string, error = "") => ({
      id: `A-match-00${n}`, name: `A-match-00${n}`, scenario: "", title: `A-match-00${n}`, student: null, seed: n,
      passed: false, score: 0, detail, error, team_error: "", sim_s: 200, replay: true, checks: [],
    });
    const report: EvaluationReport = {
      ...CLASS_REPORT,
      name: "20250101-120000-ab-vs-simple",
      title: "A/B A:match vs B:match against simple",
      kind: "ab-matches",
      passed: 0,
      score: null,
      verdict: "not significant: A:match minus B:match (win rates against simple) +0.05 has a 95 % interval -0.16 to +0.26, which contains 0",
      exercises: [],
      grades: [],
      runs: [match(1, "A:match 2 : 0 simple"), match(2, "", "the match did not finish in its time bound")],
    };
    await act(async () => t.root.render(<ReportView report={report} />));
    expect(q("eval-verdict")!.textContent).toContain("not significant");
    expect(q("eval-report")!.textContent).toContain("2 matches");
    const first = q("eval-run-A-match-001")!;
    expect(first.textContent).toContain("A:match 2 : 0 simple");
    expect(first.querySelector(".eval-fail")).toBeNull();
    expect(first.className).not.toContain("eval-row-failed");
    expect(q("eval-run-A-match-002")!.className).toContain("eval-row-failed");
  });
});
