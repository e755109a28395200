import { describe, expect, it } from "vitest";
import type { TeamError, TeamFile } from "../api/types";
import { teamFile } from "../ws/fixtures";
import { ApiError } from "../api/http";
import {
  currentFiles,
  errorIn,
  errorSummary,
  FILE_NAME_RE,
  groupFiles,
  newPlayName,
  outputRows,
  outputSignal,
  playTemplate,
  reloadedText,
  robotsText,
  stateText,
  stem,
  tickText,
} from "./files";
import { saveOutcome } from "./save";
import { stoppedByPlay, stoppedEntry, stoppedOf, stoppedText } from "./stopped";

const err = (extra: Partial<TeamError> = {}): TeamError => ({
  kind: "exception",
  message: "ZeroDivisionError: division by zero\nmore",
  file: "pass_drill.py",
  line: 12,
  traceback: "Traceback ...",
  at_unix: 1_700_000_000,
  ...extra,
});

const play = (name: string, extra: Partial<TeamFile> = {}) => teamFile(name, { kind: "play", play: stem(name), ...extra });

describe("groupFiles", () => {
  it("groups plays, processors and libraries in that order, by name, lib/ last, empty groups left out", () => {
    const files = [
      teamFile("lib/util.py"),
      play("zig.py"),
      teamFile("helpers.py"),
      play("keeper_wall.m"),
      play("attack.py"),
    ];
    const g = groupFiles(files);
    expect(g.map((x) => [x.label, x.files.map((f) => f.name)])).toEqual([
      ["Plays", ["attack.py", "keeper_wall.m", "zig.py"]],
      ["Libraries", ["helpers.py", "lib/util.py"]],
    ]);
    expect(groupFiles([teamFile("possession.py", { kind: "processor" })]).map((x) => x.label)).toEqual(["Processors"]);
    expect(groupFiles([])).toEqual([]);
  });

  it("prefers the pushed health list over GET /api/team's once there is one", () => {
    const a = [play("a.py")];
    const b = [play("b.py")];
    expect(currentFiles(b, a)).toBe(b);
    expect(currentFiles([], a)).toEqual([]); // the folder emptied since the page loaded
    expect(currentFiles(undefined, a)).toBe(a);
    expect(currentFiles(null, null)).toEqual([]);
  });
});

describe("file state texts", () => {
  it("says running with the robots, error with kind, file, line and the message's first line", () => {
    expect(stateText(play("p.py", { state: "running", robots: [3, 1] }))).toEqual({ label: "running", tone: "ok", detail: "drives 1, 3" });
    const e = stateText(play("p.py", { state: "error", error: err() }));
    expect(e.label).toBe("error");
    expect(e.tone).toBe("bad");
    expect(e.detail).toBe("exception at pass_drill.py:12: ZeroDivisionError: division by zero");
    expect(errorSummary(err({ kind: "missing", line: null, message: "" }))).toBe("missing at pass_drill.py");
    expect(stateText(play("p.py", { state: "starting" })).tone).toBe("busy");
    expect(stateText(teamFile("lib/u.py")).detail).toMatch(/library/);
    expect(stateText(play("p.py")).detail).toMatch(/choose it/);
  });

  it("formats tick times, the reload time and the robots", () => {
    expect(tickText({ tick_ms_p50: null, tick_ms_p99: null })).toBe("—");
    expect(tickText({ tick_ms_p50: 0.213, tick_ms_p99: 12.34 })).toBe("p50 0.21 ms · p99 12.3 ms");
    expect(robotsText([])).toBe("no robots");
    expect(robotsText([5, 1, 2])).toBe("1, 2, 5");
    const at = new Date(2026, 0, 2, 14, 3, 7).getTime() / 1000;
    expect(reloadedText(at, at + 12.6)).toBe("14:03:07 (12 s ago)");
    expect(reloadedText(at, at + 150)).toBe("14:03:07 (2 min ago)");
    expect(reloadedText(null, at)).toBe("not loaded");
  });

  it("lists a processor's outputs by key with their plot signal", () => {
    expect(outputRows({ ours: 0.71234, near_ours_mm: 1234.5, n: 3 })).toEqual([
      ["n", "3"],
      ["near_ours_mm", "1235"],
      ["ours", "0.712"],
    ]);
    expect(outputRows(null)).toEqual([]);
    expect(outputSignal({ name: "possession.py" }, "ours")).toBe("team.possession.ours");
  });
});

describe("errorIn: the error to mark in the editor", () => {
  it("is the file's own error with its line", () => {
    const files = [play("pass_drill.py", { state: "error", error: err() })];
    expect(errorIn("pass_drill.py", files)).toMatchObject({ line: 12, of: "pass_drill.py" });
    expect(errorIn("other.py", files)).toBeNull();
  });

  it("marks a library's line when a play failed inside it, not the play's", () => {
    const files = [play("pass_drill.py", { state: "error", error: err({ file: "lib/util.py", line: 5 }) }), teamFile("lib/util.py")];
    expect(errorIn("lib/util.py", files)).toMatchObject({ line: 5, of: "pass_drill.py" });
    const own = errorIn("pass_drill.py", files)!;
    expect(own.line).toBeNull(); // the line is in another file
    expect(own.error.file).toBe("lib/util.py");
  });

  it("ignores an error of a file that runs again", () => {
    expect(errorIn("pass_drill.py", [play("pass_drill.py", { state: "running", error: err() })])).toBeNull();
  });
});

describe("stopped robots", () => {
  const stopped = [
    { id: 4, play: "pass_drill", reason: "exception at pass_drill.py:12: boom" },
    { id: 2, play: "pass_drill", reason: "exception at pass_drill.py:12: boom" },
    { id: 1, play: "keeper_wall", reason: "budget at keeper_wall.m" },
  ];
  it("groups them by play for the Code tab", () => {
    expect(stoppedByPlay(stopped)).toEqual([
      { play: "keeper_wall", ids: [1], reason: "budget at keeper_wall.m" },
      { play: "pass_drill", ids: [2, 4], reason: "exception at pass_drill.py:12: boom" },
    ]);
    expect(stoppedOf({ play: "pass_drill" }, stopped)).toEqual([2, 4]);
    expect(stoppedOf({ play: null }, stopped)).toEqual([]);
  });
  it("finds our robot's entry (not the other team's robot with the same id)", () => {
    const strategy = { our_team: "blue", stopped };
    expect(stoppedEntry(strategy, "blue", 4)?.play).toBe("pass_drill");
    expect(stoppedEntry(strategy, "yellow", 4)).toBeNull();
    expect(stoppedEntry(null, "blue", 4)).toBeNull();
    expect(stoppedText(stopped[0]!)).toBe("play pass_drill failed, robot stopped: exception at pass_drill.py:12: boom");
  });
});

describe("new plays", () => {
  it("names the file after the play and refuses bad or taken names", () => {
    expect(newPlayName("My drill", "python", [], [])).toEqual({ name: "my_drill.py", error: null });
    expect(newPlayName("wall.m", "octave", [], [])).toEqual({ name: "wall.m", error: null });
    expect(newPlayName("  ", "python", [], []).error).toMatch(/name/);
    expect(newPlayName("3rd", "python", [], []).error).toMatch(/letter first/);
    expect(newPlayName("a/b", "python", [], []).error).toMatch(/letter first/);
    expect(newPlayName("pass_drill", "python", ["pass_drill.py"], []).error).toBe("pass_drill.py exists already");
    expect(newPlayName("match", "python", [], ["match", "defend"]).error).toBe("a play is called match already");
  });

  it("makes templates the station's discovery takes as a play of that name", () => {
    const py = playTemplate("my_drill.py", "python");
    expect(py).toMatch(/^def play\(game: Game\)/m);
    expect(py).toMatch(/^TITLE = "My drill"$/m);
    const m = playTemplate("wall.m", "octave");
    // the first code line: a function named after the file (discovery's rule for an .m play)
    expect(m.split("\n")[0]).toBe("function orders = wall(ours, theirs, ball, game)");
    expect(m.split("\n")[1]).toBe("  % Wall");
    expect(FILE_NAME_RE.test("lib/util.m")).toBe(true);
    expect(FILE_NAME_RE.test("../x.py")).toBe(false);
  });
});

describe("saveOutcome", () => {
  it("tells a conflict, a refusal and other failures apart", () => {
    expect(saveOutcome(new ApiError(409, "pass_drill.py changed on disk"))).toEqual({ kind: "conflict", message: "pass_drill.py changed on disk" });
    expect(saveOutcome(new ApiError(403, "code editing is off"))).toEqual({ kind: "denied", message: "code editing is off" });
    expect(saveOutcome(new ApiError(401, "log in")).kind).toBe("denied");
    expect(saveOutcome(new ApiError(413, "too large")).kind).toBe("error");
    expect(saveOutcome(new ApiError(0, "cannot reach the station")).kind).toBe("error");
    expect(saveOutcome(new Error("x"))).toEqual({ kind: "error", message: "x" });
  });
});
