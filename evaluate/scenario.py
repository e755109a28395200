"""Scenario files (TOML, read with the standard library's ``tomllib``): what is placed on the
field, what the referee says when, how long, which seed, fieldsim's noise and latency, and the
checks that score what happened. docs/evaluate.md describes every field.

Units are SI (m, m/s, s; headings in degrees as ``heading_deg`` or radians as ``heading``),
and every position is in **our frame**: our goal at negative x, as a team's play sees the
field (``[ours] side`` says where our goal is on the real field). A bad file is refused with a
:class:`ScenarioError` that names the file and the field (``robots[1].x: expected a number,
got 'abc'``); an unknown field is an error too (a typo must not pass silently).
"""

from __future__ import annotations

import ast
import copy
import math
import random
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from backend.params.model import PLAYS
from domain.rules import COMMANDS, command_team

TeamSide = Literal["ours", "theirs"]

#: referee commands a scenario may give, from the one list (domain.rules); the team ones take
#: ``team = "ours" | "theirs"``. Not offered: the deprecated GOAL_* and INDIRECT_FREE_*.
_DEPRECATED = ("GOAL", "INDIRECT_FREE")
PLAIN_COMMANDS = tuple(c for c in COMMANDS if command_team(c) is None)
TEAM_COMMANDS = tuple(c.removesuffix("_BLUE") for c in COMMANDS if c.endswith("_BLUE")
                      and c.removesuffix("_BLUE") not in _DEPRECATED)
#: fieldsim settings a scenario may change (``[sim]``), each with its allowed range
SIM_FIELDS: dict[str, tuple[float, float]] = {
    "noise_mm": (0.0, 100.0), "noise_rad": (0.0, 1.0), "miss_prob": (0.0, 1.0),
    "false_prob": (0.0, 1.0), "camera_hz": (10.0, 200.0), "generation": (1, 2),
    "robot_max_speed": (0.1, 10.0), "robot_max_accel": (0.1, 20.0),
    "ball_rolling_decel": (0.0, 5.0), "gain_min": (0.1, 2.0), "gain_max": (0.1, 2.0),
}
LATENCY_FIELDS = ("vision_latency_ms", "command_latency_ms")
END_EVENTS = ("goal", "ball_out")
#: play names: a built-in play or a team play's file stem
PLAY_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]{0,63}$")
MAX_RUNS = 1000
MAX_DURATION_S = 900.0
MAX_ROBOT_ID = 15


class ScenarioError(ValueError):
    """A scenario file that cannot be used: ``where`` is the file, ``field`` the dotted
    field (empty: the file as a whole)."""

    def __init__(self, where: str, field: str, message: str) -> None:
        self.where, self.field, self.message = where, field, message
        super().__init__(f"{where}: {field}: {message}" if field else f"{where}: {message}")


@dataclass(frozen=True)
class Placement:
    """A robot placed at the start: our frame, m, rad."""

    team: TeamSide
    id: int
    x: float
    y: float
    heading: float = 0.0


@dataclass(frozen=True)
class BallState:
    x: float
    y: float
    vx: float = 0.0
    vy: float = 0.0


@dataclass(frozen=True)
class RefereeStep:
    at: float  # s from the start
    command: str  # PLAIN_COMMANDS or TEAM_COMMANDS
    team: TeamSide | None = None
    designated: tuple[float, float] | None = None  # BALL_PLACEMENT: our frame, m
    #: NORMAL_START only: given as soon as the robots are ready, as the game controller does
    #: (``runner.READY_RULE``), ``at`` being the latest (its prepare timeout)
    when_ready: bool = False

    def label(self) -> str:
        return self.command if self.team is None else f"{self.command} ({self.team})"


@dataclass(frozen=True)
class Action:
    """At ``at`` s: the ball put somewhere with a velocity (a shot, a pass to receive), or a
    robot moved (our frame, m, m/s, rad)."""

    at: float
    ball: BallState | None = None
    robot: Placement | None = None


@dataclass(frozen=True)
class OperatorTarget:
    """A target as an operator would click it in the page (our frame, m, rad)."""

    id: int
    x: float
    y: float
    heading: float | None = None


@dataclass(frozen=True)
class CheckSpec:
    name: str
    params: Mapping[str, Any]
    weight: float = 1.0
    label: str = ""


@dataclass(frozen=True)
class Scenario:
    """One scenario as loaded; ``runs`` > 1 with ``vary``: each run draws its own values."""

    name: str  # the file stem
    path: str  # where it was read (for messages)
    title: str
    statement: str
    duration_s: float
    seed: int
    runs: int
    division: str
    cameras: int
    sim: Mapping[str, float]
    vision_latency_ms: float
    command_latency_ms: float
    our_team: Literal["blue", "yellow"]
    our_side: Literal["negative-x", "positive-x"]
    play: str | None  # the play under test (None: the one given on the command line)
    params: Mapping[str, Any]  # parameter overrides (dotted names) for our side
    opponent_play: str | None  # None: their robots stand still, nothing drives them
    opponent_params: Mapping[str, Any]
    robots: tuple[Placement, ...]
    ball: BallState | None
    referee: tuple[RefereeStep, ...]
    actions: tuple[Action, ...]
    operator_targets: tuple[OperatorTarget, ...]
    task: Mapping[str, Any]
    checks: tuple[CheckSpec, ...]
    end_on: tuple[str, ...]
    tags: tuple[str, ...]
    vary: Mapping[str, tuple[float, float]]
    raw: Mapping[str, Any] = field(repr=False, compare=False, default_factory=dict)

    def for_run(self, index: int) -> Scenario:
        """The scenario of run ``index`` (0-based): its seed is ``seed + index`` and each
        ``vary`` field is drawn uniformly from its range with that run's own random stream."""
        if index == 0 and not self.vary:
            return self
        data = copy.deepcopy(dict(self.raw))
        rng = random.Random(f"evaluate-{self.seed}-{index}")
        for dotted, (lo, hi) in sorted(self.vary.items()):
            _set_path(data, dotted, rng.uniform(lo, hi), self.path)
        data["seed"] = self.seed + index
        data.pop("vary", None)
        data["runs"] = 1
        return parse_scenario(data, self.name, self.path, custom_checks=None)

    @property
    def ours(self) -> tuple[Placement, ...]:
        return tuple(r for r in self.robots if r.team == "ours")

    @property
    def theirs(self) -> tuple[Placement, ...]:
        return tuple(r for r in self.robots if r.team == "theirs")


# -- reading --------------------------------------------------------------------------------


def load_scenario(path: str | Path,
                  custom_checks: Mapping[str, CheckSignature] | None = None) -> Scenario:
    """A scenario file; ``custom_checks``: the suite's own checks (``checks.py``) by name,
    besides the built-in ones."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise ScenarioError(str(p), "", f"cannot read it: {exc.strerror or exc}") from exc
    except UnicodeDecodeError as exc:
        raise ScenarioError(str(p), "", f"not UTF-8 text ({exc.reason})") from exc
    return parse_scenario_text(text, p.stem, str(p), custom_checks)


def parse_scenario_text(text: str, name: str, where: str,
                        custom_checks: Mapping[str, CheckSignature] | None = None) -> Scenario:
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(where, "", f"not valid TOML: {exc}") from exc
    return parse_scenario(data, name, where, custom_checks)


class _Fields:
    """A table of the file, read field by field; what was not read is an unknown field."""

    def __init__(self, data: Any, where: str, prefix: str) -> None:
        if not isinstance(data, Mapping):
            raise ScenarioError(where, prefix, f"expected a table, got {_show(data)}")
        self.data, self.where, self.prefix = data, where, prefix
        self.read: set[str] = set()

    def path(self, key: str) -> str:
        return f"{self.prefix}.{key}" if self.prefix else key

    def err(self, key: str, message: str) -> ScenarioError:
        return ScenarioError(self.where, self.path(key), message)

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = None) -> Any:
        self.read.add(key)
        return self.data.get(key, default)

    def number(self, key: str, default: float | None = None, lo: float = -math.inf,
               hi: float = math.inf, unit: str = "") -> float:
        v = self.raw(key)
        if v is None:
            if default is None:
                raise self.err(key, "missing (a number" + (f", {unit}" if unit else "") + ")")
            return default
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise self.err(key, f"expected a number{' (' + unit + ')' if unit else ''}, "
                                f"got {_show(v)}")
        f = float(v)
        if not math.isfinite(f):
            raise self.err(key, f"expected a finite number, got {v}")
        if not lo <= f <= hi:
            raise self.err(key, f"{f:g} is out of range [{lo:g}, {hi:g}]")
        return f

    def integer(self, key: str, default: int | None = None, lo: int = -(2**31),
                hi: int = 2**31 - 1) -> int:
        v = self.raw(key)
        if v is None:
            if default is None:
                raise self.err(key, "missing (an integer)")
            return default
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.err(key, f"expected an integer, got {_show(v)}")
        if not lo <= v <= hi:
            raise self.err(key, f"{v} is out of range [{lo}, {hi}]")
        return v

    def text(self, key: str, default: str | None = None) -> str:
        v = self.raw(key)
        if v is None:
            if default is None:
                raise self.err(key, "missing (a string)")
            return default
        if not isinstance(v, str):
            raise self.err(key, f"expected a string, got {_show(v)}")
        return v

    def choice(self, key: str, choices: Sequence[str], default: str | None = None) -> str:
        v = self.text(key, default)
        if v not in choices:
            raise self.err(key, f"{v!r} is not one of {', '.join(choices)}")
        return v

    def flag(self, key: str, default: bool) -> bool:
        v = self.raw(key, default)
        if not isinstance(v, bool):
            raise self.err(key, f"expected true or false, got {_show(v)}")
        return v

    def point(self, key: str, default: tuple[float, float] | None = None,
              required: bool = True) -> tuple[float, float] | None:
        v = self.raw(key)
        if v is None:
            if default is None and required:
                raise self.err(key, "missing (a point [x, y] in m)")
            return default
        return _point(v, self.where, self.path(key))

    def heading(self) -> float:
        """``heading`` (rad) or ``heading_deg``; 0 when neither is given."""
        if self.has("heading") and self.has("heading_deg"):
            raise self.err("heading", "give heading (rad) or heading_deg, not both")
        if self.has("heading_deg"):
            return math.radians(self.number("heading_deg", lo=-720.0, hi=720.0, unit="deg"))
        return self.number("heading", 0.0, lo=-4 * math.pi, hi=4 * math.pi, unit="rad")

    def tables(self, key: str) -> list[_Fields]:
        v = self.raw(key, [])
        if isinstance(v, Mapping):
            v = [v]
        if not isinstance(v, list):
            raise self.err(key, f"expected an array of tables ([[{key}]]), got {_show(v)}")
        return [_Fields(item, self.where, f"{self.path(key)}[{i}]") for i, item in enumerate(v)]

    def table(self, key: str) -> _Fields:
        return _Fields(self.raw(key, {}), self.where, self.path(key))

    def done(self) -> None:
        unknown = sorted(set(self.data) - self.read)
        if unknown:
            known = ", ".join(sorted(self.read)) or "none"
            raise self.err(unknown[0], f"unknown field (known here: {known})")


def _show(v: Any) -> str:
    if isinstance(v, str):
        return repr(v)
    if isinstance(v, Mapping):
        return "a table"
    if isinstance(v, list):
        return "an array"
    return f"{v!r} ({type(v).__name__})"


def _point(v: Any, where: str, path: str) -> tuple[float, float]:
    if not isinstance(v, list) or len(v) != 2 or any(
            isinstance(c, bool) or not isinstance(c, int | float) or not math.isfinite(c)
            for c in v):
        raise ScenarioError(where, path, f"expected a point [x, y] (m), got {_show(v)}")
    return (float(v[0]), float(v[1]))


def _play(f: _Fields, key: str) -> str | None:
    v = f.raw(key)
    if v is None:
        return None
    if not isinstance(v, str) or not PLAY_NAME.match(v):
        raise f.err(key, f"expected a play name (a built-in one: {', '.join(PLAYS)}, or a "
                         f"team play's file name without .py), got {_show(v)}")
    return v


def _params(f: _Fields, key: str) -> dict[str, Any]:
    """Parameter overrides: a table of dotted names (``"strategy.kick_speed_mps" = 4.0``) or
    nested tables; checked against the station's parameters when the run starts."""
    v = f.raw(key, {})
    if not isinstance(v, Mapping):
        raise f.err(key, f"expected a table of parameters, got {_show(v)}")
    out: dict[str, Any] = {}

    def flat(prefix: str, m: Mapping[str, Any]) -> None:
        for k, val in m.items():
            name = f"{prefix}.{k}" if prefix else str(k)
            if isinstance(val, Mapping):
                flat(name, val)
            else:
                out[name] = val
    flat("", v)
    return out


def _placement(f: _Fields, team_default: TeamSide | None = None) -> Placement:
    team = f.choice("team", ("ours", "theirs"), team_default)
    p = Placement(team, f.integer("id", lo=0, hi=MAX_ROBOT_ID),  # type: ignore[arg-type]
                  f.number("x", unit="m", lo=-7.0, hi=7.0),
                  f.number("y", unit="m", lo=-5.5, hi=5.5), f.heading())
    f.done()
    return p


def _ball(f: _Fields) -> BallState:
    """A ball's place and velocity: ``vx``, ``vy``, or ``speed`` towards the point ``aim`` (a
    shot at a spot: ``vary`` its ``aim[1]`` and every run's shot is on target, which
    independent ranges of vx and vy cannot say)."""
    x = f.number("x", unit="m", lo=-7.0, hi=7.0)
    y = f.number("y", unit="m", lo=-5.5, hi=5.5)
    if f.has("aim") or f.has("speed"):
        if f.has("vx") or f.has("vy"):
            raise f.err("aim", "give vx and vy, or aim and speed, not both")
        aim = f.point("aim")
        assert aim is not None  # (required: point raises when it is missing)
        speed = f.number("speed", lo=0.0, hi=10.0, unit="m/s")
        d = math.hypot(aim[0] - x, aim[1] - y)
        if d == 0.0:
            raise f.err("aim", "the ball is at its aim: no direction to shoot in")
        b = BallState(x, y, speed * (aim[0] - x) / d, speed * (aim[1] - y) / d)
    else:
        b = BallState(x, y, f.number("vx", 0.0, lo=-10.0, hi=10.0, unit="m/s"),
                      f.number("vy", 0.0, lo=-10.0, hi=10.0, unit="m/s"))
    f.done()
    return b


def parse_scenario(data: Mapping[str, Any], name: str, where: str,
                   custom_checks: Mapping[str, CheckSignature] | None = None) -> Scenario:
    """A scenario from its TOML data (``name``: the file stem, ``where``: for messages)."""
    from .checks import builtin_signatures  # (checks import this module's types)

    top = _Fields(data, where, "")
    title = top.text("title", name)
    statement = top.text("statement", "")
    duration = top.number("duration_s", lo=0.5, hi=MAX_DURATION_S, unit="s")
    seed = top.integer("seed", 1, lo=0, hi=2**31 - 1)
    runs = top.integer("runs", 1, lo=1, hi=MAX_RUNS)
    tags = top.raw("tags", [])
    if not isinstance(tags, list) or not all(isinstance(t, str) for t in tags):
        raise top.err("tags", f"expected an array of strings, got {_show(tags)}")
    end_on = top.raw("end_on", [])
    if not isinstance(end_on, list) or any(e not in END_EVENTS for e in end_on):
        raise top.err("end_on", f"expected an array of {', '.join(END_EVENTS)}, got "
                                f"{_show(end_on)}")

    fld = top.table("field")
    division = fld.choice("division", ("A", "B"), "B")
    cameras = fld.integer("cameras", 4)
    if cameras not in (1, 2, 4, 8):
        raise fld.err("cameras", f"{cameras} cameras: fieldsim has 1, 2, 4 or 8")
    fld.done()

    simf = top.table("sim")
    sim: dict[str, float] = {}
    for key, (lo, hi) in SIM_FIELDS.items():
        if simf.has(key):
            sim[key] = (simf.integer(key, lo=int(lo), hi=int(hi)) if key == "generation"
                        else simf.number(key, lo=lo, hi=hi))
    lat = {k: simf.number(k, 0.0, lo=0.0, hi=500.0, unit="ms") for k in LATENCY_FIELDS}
    simf.done()

    ours = top.table("ours")
    our_team = ours.choice("team", ("blue", "yellow"), "blue")
    our_side = ours.choice("side", ("negative-x", "positive-x"), "negative-x")
    play = _play(ours, "play")
    params = _params(ours, "params")
    targets: list[OperatorTarget] = []
    for t in ours.tables("operator_targets"):
        heading = t.heading() if (t.has("heading") or t.has("heading_deg")) else None
        targets.append(OperatorTarget(t.integer("id", lo=0, hi=MAX_ROBOT_ID),
                                      t.number("x", unit="m", lo=-7.0, hi=7.0),
                                      t.number("y", unit="m", lo=-5.5, hi=5.5), heading))
        t.done()
    ours.done()

    opp = top.table("opponent")
    opponent_play = _play(opp, "play")
    if opponent_play == "none":
        opponent_play = None
    opponent_params = _params(opp, "params")
    opp.done()

    robots = [_placement(r) for r in top.tables("robots")]
    seen: set[tuple[str, int]] = set()
    for i, r in enumerate(robots):
        if (r.team, r.id) in seen:
            raise ScenarioError(where, f"robots[{i}]", f"{r.team} robot {r.id} is placed twice")
        seen.add((r.team, r.id))
    if not any(r.team == "ours" for r in robots):
        raise top.err("robots", "no robot of ours is placed ([[robots]] with team = \"ours\")")
    ball = _ball(top.table("ball")) if top.has("ball") else None
    if ball is None:
        top.raw("ball")

    referee: list[RefereeStep] = []
    for rf in top.tables("referee"):
        at = rf.number("at", 0.0, lo=0.0, hi=duration, unit="s")
        cmd = rf.choice("command", (*PLAIN_COMMANDS, *TEAM_COMMANDS))
        team: TeamSide | None = None
        if cmd in TEAM_COMMANDS:
            team = "ours" if rf.choice("team", ("ours", "theirs")) == "ours" else "theirs"
        designated = rf.point("designated", required=False)
        when_ready = rf.choice("when", ("at", "ready"), "at") == "ready"
        if when_ready and cmd != "NORMAL_START":
            raise rf.err("when", f"only a NORMAL_START waits for the robots, not {cmd}")
        if cmd == "BALL_PLACEMENT" and designated is None:
            raise rf.err("designated", "BALL_PLACEMENT needs a designated point [x, y] (m)")
        if cmd != "BALL_PLACEMENT" and designated is not None:
            raise rf.err("designated", f"only BALL_PLACEMENT has one, not {cmd}")
        rf.done()
        referee.append(RefereeStep(at, cmd, team, designated, when_ready))
    for i in range(1, len(referee)):
        if referee[i].at < referee[i - 1].at:
            raise ScenarioError(where, f"referee[{i}].at", "the referee's steps go in time "
                                f"order ({referee[i].at:g} s after {referee[i - 1].at:g} s)")
    for i, step in enumerate(referee):
        prev = referee[i - 1].command if i else None
        if step.command == "NORMAL_START" and prev not in ("PREPARE_KICKOFF", "PREPARE_PENALTY"):
            raise ScenarioError(where, f"referee[{i}].command",
                                "NORMAL_START follows a PREPARE_KICKOFF or PREPARE_PENALTY")

    actions: list[Action] = []
    for a in top.tables("actions"):
        at = a.number("at", lo=0.0, hi=duration, unit="s")
        b = _ball(a.table("ball")) if a.has("ball") else None
        rob = _placement(a.table("robot"), "ours") if a.has("robot") else None
        if (b is None) == (rob is None):
            raise ScenarioError(where, a.prefix, "an action moves the ball or a robot "
                                "(ball = {...} or robot = {...}), one of them")
        a.done()
        actions.append(Action(at, b, rob))
    actions.sort(key=lambda a: a.at)

    task = top.raw("task", {})
    if not isinstance(task, Mapping):
        raise top.err("task", f"expected a table, got {_show(task)}")

    sigs = dict(builtin_signatures())
    if custom_checks:
        sigs.update(custom_checks)
    checks = [_check(c, sigs) for c in top.tables("check")]
    if not checks:
        raise top.err("check", "no check: a scenario scores what happened with at least one "
                               "[[check]] (docs/evaluate.md lists them)")

    vary_raw = top.raw("vary", {})
    if not isinstance(vary_raw, Mapping):
        raise top.err("vary", f"expected a table of \"field\" = [low, high], got "
                              f"{_show(vary_raw)}")
    vary: dict[str, tuple[float, float]] = {}
    for k, v in vary_raw.items():
        lo_hi = _point(v, where, f"vary.{k}")
        if lo_hi[0] > lo_hi[1]:
            raise ScenarioError(where, f"vary.{k}", "low > high")
        _set_path(copy.deepcopy(dict(data)), k, lo_hi[0], where)  # the field must exist
        vary[k] = lo_hi
    top.done()
    return Scenario(
        name=name, path=where, title=title, statement=statement, duration_s=duration,
        seed=seed, runs=runs, division=division, cameras=cameras, sim=sim,
        vision_latency_ms=lat["vision_latency_ms"],
        command_latency_ms=lat["command_latency_ms"], our_team=our_team,  # type: ignore[arg-type]
        our_side=our_side, play=play, params=params,  # type: ignore[arg-type]
        opponent_play=opponent_play, opponent_params=opponent_params, robots=tuple(robots),
        ball=ball, referee=tuple(referee), actions=tuple(actions),
        operator_targets=tuple(targets), task=dict(task), checks=tuple(checks),
        end_on=tuple(end_on), tags=tuple(tags), vary=vary, raw=dict(data))


# -- checks named in a scenario ---------------------------------------------------------------


@dataclass(frozen=True)
class CheckSignature:
    """A check's parameters: name -> kind ("number", "integer", "point", "bool", "text",
    "points", "any"), and which of them are required."""

    params: Mapping[str, str]
    required: frozenset[str]


def _check(f: _Fields, sigs: Mapping[str, CheckSignature]) -> CheckSpec:
    name = f.text("name")
    sig = sigs.get(name)
    if sig is None:
        raise f.err("name", f"unknown check {name!r} (built-in: {', '.join(sorted(sigs))}; "
                            f"a suite's own go in its checks.py)")
    weight = f.number("weight", 1.0, lo=0.0, hi=1000.0)
    label = f.text("label", "")
    params: dict[str, Any] = {}
    for key, kind in sig.params.items():
        if not f.has(key):
            if key in sig.required:
                raise f.err(key, f"missing: check {name!r} needs it")
            continue
        if kind == "number":
            params[key] = f.number(key)
        elif kind == "integer":
            params[key] = f.integer(key)
        elif kind == "point":
            params[key] = f.point(key)
        elif kind == "bool":
            params[key] = f.flag(key, False)
        elif kind == "text":
            params[key] = f.text(key)
        elif kind == "texts":
            v = f.raw(key)
            if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
                raise f.err(key, f"expected an array of strings, got {_show(v)}")
            params[key] = tuple(v)
        else:
            params[key] = f.raw(key)
    f.done()
    return CheckSpec(name, params, weight, label)


def check_signature_from_ast(fn: ast.FunctionDef) -> CheckSignature:
    """A custom check's parameters read from its source (checks.py is never imported where
    scenarios are only listed: the station reads a team's files without running them)."""
    args = fn.args
    names = [a.arg for a in args.args[1:]] + [a.arg for a in args.kwonlyargs]
    n_def = len(args.defaults)
    positional = [a.arg for a in args.args[1:]]
    required = set(positional[:len(positional) - n_def] if n_def else positional)
    required |= {a.arg for a, d in zip(args.kwonlyargs, args.kw_defaults, strict=True)
                 if d is None}
    kinds = {}
    for a in [*args.args[1:], *args.kwonlyargs]:
        kinds[a.arg] = _kind_of(a.annotation)
    return CheckSignature({n: kinds[n] for n in names}, frozenset(required))


def _kind_of(ann: ast.expr | None) -> str:
    text = ast.unparse(ann) if ann is not None else ""
    text = text.replace(" ", "")
    if text in ("float", "float|None"):
        return "number"
    if text in ("int", "int|None"):
        return "integer"
    if text == "bool":
        return "bool"
    if text in ("str", "str|None"):
        return "text"
    if text.startswith("tuple[float,float]") or text == "Point" or text == "Point|None":
        return "point"
    return "any"


# -- vary: dotted paths into the data -------------------------------------------------------

_PART = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")


def _set_path(data: dict[str, Any], dotted: str, value: float, where: str) -> None:
    """``robots[0].x``, ``actions[2].ball.vy``, ``task.target[1]`` := value."""
    cur: Any = data
    parts = dotted.split(".")
    steps: list[str | int] = []
    for part in parts:
        m = _PART.match(part)
        if m is None:
            raise ScenarioError(where, f"vary.{dotted}", "not a field path (like robots[0].x)")
        steps.append(m.group(1))
        steps.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    for i, step in enumerate(steps):
        last = i == len(steps) - 1
        try:
            if last:
                old = cur[step]
                if isinstance(old, bool) or not isinstance(old, int | float):
                    raise ScenarioError(where, f"vary.{dotted}", "varies a number only")
                cur[step] = value
            else:
                cur = cur[step]
        except (KeyError, IndexError, TypeError):
            raise ScenarioError(where, f"vary.{dotted}", "no such field in this scenario "
                                "(give it a value to vary from)") from None


# -- suites -----------------------------------------------------------------------------------

SUITES_DIR = Path(__file__).resolve().parent / "suites"


@dataclass(frozen=True)
class Suite:
    name: str
    folder: str
    scenarios: tuple[Scenario, ...]
    checks_file: str | None  # the suite's own checks.py, if it has one


def resolve_suite(name_or_path: str) -> Path:
    """A shipped suite by name (``exercises``, ``regression``) or a folder."""
    p = Path(name_or_path)
    if re.match(r"^[A-Za-z0-9_-]+$", name_or_path) and (SUITES_DIR / name_or_path).is_dir():
        return SUITES_DIR / name_or_path
    return p


def shipped_suites() -> list[str]:
    return sorted(p.name for p in SUITES_DIR.iterdir() if p.is_dir()
                  and any(p.glob("*.toml"))) if SUITES_DIR.is_dir() else []


def custom_check_signatures(checks_py: Path) -> dict[str, CheckSignature]:
    """The public functions of a suite's checks.py, read from its source (not imported)."""
    where = str(checks_py)
    try:
        tree = ast.parse(checks_py.read_text(encoding="utf-8"), filename=where)
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(where, "", f"cannot read it: {exc}") from exc
    except SyntaxError as exc:
        raise ScenarioError(where, "", f"line {exc.lineno}: {exc.msg}") from exc
    return {node.name: check_signature_from_ast(node) for node in tree.body
            if isinstance(node, ast.FunctionDef) and not node.name.startswith("_")}


def load_suite(name_or_path: str) -> Suite:
    """Every ``*.toml`` of a folder, in name order, and its checks.py (read, not run)."""
    folder = resolve_suite(name_or_path)
    if not folder.is_dir():
        known = ", ".join(shipped_suites())
        raise ScenarioError(name_or_path, "", f"no such suite folder (shipped suites: {known})")
    checks_py = folder / "checks.py"
    custom = custom_check_signatures(checks_py) if checks_py.is_file() else None
    files = sorted(folder.glob("*.toml"))
    if not files:
        raise ScenarioError(str(folder), "", "no scenario (*.toml) in this folder")
    scenarios = tuple(load_scenario(f, custom) for f in files)
    return Suite(folder.name, str(folder), scenarios,
                 str(checks_py) if checks_py.is_file() else None)
