"""By-hand check of the official ssl-game-controller's checks that use a tracker, with Touchline
as its only tracker source (docs/tracker.md, "The game controller's tracker checks").

The GC judges placements, readiness and progress from the tracked ball and robots it receives
(its engine's ``trackerStateGc``); it never shows them. This script drives the GC through its
UI websocket (``/api/control``, protojson ``Input``), watches what it decides (commands, game
events, continue actions and their issues) and prints beside it the tracked ball the GC was
sent (Touchline's multicast, the same frames) and fieldsim's ground truth (``--truth-pub``).

The GC and the station are not started here; docs/tracker.md has the commands. Scenarios:

- ``placement-timeout``: the ball put outside a touch line, a BALL_LEFT_FIELD_TOUCH_LINE event
  by yellow; the GC asks blue (Touchline, "match" play) to place; nobody says the placement
  succeeded, so after its placement time the GC itself files PLACEMENT_FAILED with the
  remaining distance from its tracker; then what it offers in STOP.
- ``placement-complete``: the same, but the operator presses "placement complete" once the
  tracked ball rests at the mark; then what the GC offers (its ready checks in STOP).
- ``stop-ready``: STOP with the ball next to a blue robot; how long the GC's "robots too close
  to ball" issue lasts while Touchline's robots clear the ball.
- ``no-progress``: FORCE_START with the ball left alone (the station's "idle" play for the
  time); the GC's NO_PROGRESS_IN_GAME and the location it reports.
- ``rest``: HALT, the ball at rest at a few spots: how many tracked frames carry a speed over
  the GC's 0.2 m/s "steady" threshold (single-frame spikes in camera overlaps).

The next scenarios need ``--sim-control-port`` (fieldsim's SimulatorCommand port: the other
team, which nobody drives, is put in place by teleports, and robots are taken off). They read
the station's colour from ``/api/params`` (``team.our_team``), so they also run with
``launcher --our-team yellow``; auto continue is off while they run (the GC stays in the
prepare command and only says whether it would continue):

- ``kickoff``: for each team, the ball at the centre, KICKOFF: when the GC's NORMAL_START has no
  issue left; then one robot of the other team (nobody drives it) teleported into the wrong
  half (the GC must name it and keep naming it), and one of ours (Touchline must bring it back).
- ``penalty``: for each team, the ball on the penalty mark, the other team placed by teleport
  (its keeper on its goal line, the rest 1 m behind the ball), PENALTY: when it is ready; then
  one of ours put in front of the ball, and when we defend our keeper taken out of the goal.
- ``robot-count``: STOP, a yellow card for each team in turn: the GC's "too many robots" while
  the team has more robots on the field than it is allowed; the excess robot (ours: the one
  Touchline sends to the halfway line; theirs: any) taken off fieldsim: when the issue clears.
- ``card-running``: a yellow card for us during FORCE_START, the robot Touchline sends off taken
  off ``--lift-after`` s later: whether the GC files TOO_MANY_ROBOTS (after the card's 10 s).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import socket
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

import httpx
import websockets
import zmq
import zmq.asyncio

from fieldsim.bodies import formation
from fieldsim.geometry import division_geometry
from sslnet.multicast import open_multicast_receiver
from sslpb import ssl_gc_common_pb2 as gc_common_pb
from sslpb import ssl_simulation_control_pb2 as control_pb
from sslpb import ssl_vision_wrapper_tracked_pb2 as wrapper_pb

CLOSE_TIMEOUT_S = 0.2
PLACEMENT_TOLERANCE_M = 0.15  # the GC's ball-placement-tolerance
PREPARATION = "s left for preparation"  # the GC's own waiting issue, not a readiness issue


@dataclass
class Seen:
    match: dict[str, Any] = field(default_factory=dict)
    gc: dict[str, Any] = field(default_factory=dict)
    changes: set[str] = field(default_factory=set)  # ids restart at a match reset
    events: list[str] = field(default_factory=list)  # game event types as they were filed
    tracked: tuple[float, float, float, float] | None = None  # x, y m, speed m/s, at (monotonic)
    tracked_robots: list[tuple[str, int, float, float]] = field(default_factory=list)
    truth: tuple[float, float] | None = None  # m
    truth_robots: list[tuple[str, int, float, float, float]] = field(default_factory=list)
    truth_ball_speed: float = 0.0  # m/s
    truth_touch: Any = None  # fieldsim's last_touch
    truth_kicks: dict[tuple[str, int], Any] = field(default_factory=dict)
    unsteady: int = 0  # tracked frames over the GC's 0.2 m/s "steady" while the truth rests
    unsteady_max: float = 0.0
    frames: int = 0  # tracked frames with a ball
    quiet: bool = False  # no line per unsteady frame (the rest scenario counts them)
    t0: float = field(default_factory=time.monotonic)

    def t(self) -> float:
        return time.monotonic() - self.t0

    def command(self) -> str:
        c = self.match.get("command") or {}
        team = c.get("forTeam", "UNKNOWN")
        return f"{c.get('type')}{'' if team == 'UNKNOWN' else ' ' + team}"

    def placement_pos(self) -> tuple[float, float] | None:
        p = self.match.get("placementPos")
        return (p.get("x", 0.0), p.get("y", 0.0)) if p else None

    def actions(self) -> str:
        out = []
        for a in self.gc.get("continueActions") or []:
            team = a.get("forTeam", "UNKNOWN")
            issues = "; ".join(a.get("continuationIssues") or [])
            out.append(f"{a.get('type')}{'' if team == 'UNKNOWN' else ' ' + team} "
                       f"[{a.get('state')}]{' (' + issues + ')' if issues else ''}")
        hints = [h.get("message", "") for h in self.gc.get("continueHints") or []]
        return " | ".join(out + [f"hint: {h}" for h in hints])

    def balls(self) -> str:
        tr = f"({self.tracked[0]:.3f}, {self.tracked[1]:.3f}) v {self.tracked[2]:.2f}" \
            if self.tracked else "none"
        th = f"({self.truth[0]:.3f}, {self.truth[1]:.3f})" if self.truth else "none"
        s = f"tracked {tr}, truth {th}"
        pos = self.placement_pos()
        if pos and self.tracked and self.truth:
            s += (f"; to mark: tracked {math.dist(pos, self.tracked[:2]):.3f} m, "
                  f"truth {math.dist(pos, self.truth):.3f} m")
        return s


async def gc_reader(ws: Any, seen: Seen) -> None:
    async for raw in ws:
        out = json.loads(raw)
        if out.get("matchState"):
            before = seen.command()
            seen.match = out["matchState"]
            if seen.command() != before:
                print(f"{seen.t():6.2f} GC command {seen.command()}; {seen.balls()}")
        if out.get("gcState"):
            before = seen.actions()
            trackers = seen.gc.get("trackers")
            seen.gc = out["gcState"]
            if seen.gc.get("trackers") != trackers and trackers is not None:
                # without a tracker source the GC finds no issue at all (no data, no check)
                print(f"{seen.t():6.2f} GC trackers now {seen.gc.get('trackers') or 'none'}")
            if seen.actions() != before:
                print(f"{seen.t():6.2f} GC continue: {seen.actions()}")
        for entry in (out.get("protocol") or {}).get("entry") or []:
            key = json.dumps(entry.get("change"), sort_keys=True)
            if key in seen.changes:
                continue
            seen.changes.add(key)
            ge = (entry.get("change") or {}).get("addGameEventChange")
            if ge and seen.match:
                seen.events.append(ge["gameEvent"].get("type", "?"))
                print(f"{seen.t():6.2f} GC game event {json.dumps(ge['gameEvent'])}; "
                      f"{seen.balls()}")


async def tracked_reader(seen: Seen, group: str, port: int) -> None:
    sock = open_multicast_receiver(group, port)
    loop = asyncio.get_running_loop()
    try:
        while True:
            data = await loop.sock_recv(sock, 65536)
            packet = wrapper_pb.TrackerWrapperPacket()
            packet.ParseFromString(data)
            f = packet.tracked_frame
            if f.balls:
                b = f.balls[0]
                seen.tracked = (b.pos.x, b.pos.y, math.hypot(b.vel.x, b.vel.y), time.monotonic())
                seen.frames += 1
                if seen.tracked[2] >= 0.2 and seen.truth_ball_speed < 0.01:
                    seen.unsteady += 1
                    seen.unsteady_max = max(seen.unsteady_max, seen.tracked[2])
                    if not seen.quiet:
                            print(f"{seen.t():6.2f} tracked ball at {seen.tracked[2]:.2f} m/s "
                              f"while the true ball rests ({seen.truth_ball_speed:.3f} m/s); "
                              f"{seen.balls()}")
            seen.tracked_robots = [
                ("blue" if r.robot_id.team == 2 else "yellow", r.robot_id.id, r.pos.x, r.pos.y)
                for r in f.robots]
    finally:
        sock.close()


async def truth_reader(seen: Seen, endpoint: str) -> None:
    ctx = zmq.asyncio.Context()
    sock = ctx.socket(zmq.SUB)
    sock.setsockopt(zmq.SUBSCRIBE, b"truth")
    sock.connect(endpoint)
    try:
        while True:
            _, body = await sock.recv_multipart()
            t = json.loads(body)
            seen.truth = (t["ball"]["x"] / 1000.0, t["ball"]["y"] / 1000.0)
            seen.truth_ball_speed = math.hypot(t["ball"]["vx"], t["ball"]["vy"]) / 1000.0
            seen.truth_touch = t.get("last_touch")
            seen.truth_kicks = {(r["team"], r["id"]): r.get("kicks") for r in t["robots"]}
            seen.truth_robots = [(r["team"], r["id"], r["x"] / 1000.0, r["y"] / 1000.0,
                                  math.hypot(r["vx"], r["vy"]) / 1000.0) for r in t["robots"]]
    finally:
        sock.close(linger=0)
        ctx.term()


class Check:
    def __init__(self, a: argparse.Namespace, ws: Any, seen: Seen) -> None:
        self.a, self.ws, self.seen = a, ws, seen
        self.http = httpx.AsyncClient(base_url=f"http://{a.station}", timeout=5.0)
        self.sim = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)

    async def send(self, message: dict[str, Any]) -> None:
        await self.ws.send(json.dumps(message))

    async def command(self, kind: str, team: str = "UNKNOWN") -> None:
        await self.send({"change": {"newCommandChange": {"command": {"type": kind,
                                                                     "forTeam": team}}}})
        await self.until(lambda: self.seen.command() == (kind if team == "UNKNOWN"
                                                         else f"{kind} {team}"),
                         5, f"GC command {kind}")

    async def ball(self, x: float, y: float) -> None:
        r = await self.http.post("/api/sim/ball", json={"x": x * 1000.0, "y": y * 1000.0})
        r.raise_for_status()

    async def play(self, name: str) -> None:
        r = await self.http.patch("/api/params", json={"strategy": {"play": name}})
        r.raise_for_status()

    async def until(self, cond: Any, timeout_s: float, what: str) -> bool:
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            if cond():
                return True
            await asyncio.sleep(0.05)
        print(f"{self.seen.t():6.2f} (not within {timeout_s} s: {what})")
        return False

    async def setup(self) -> None:
        """DIV_B (fieldsim's 9 m x 6 m field), a friendly, auto continue on, from a clean
        match; STOP, FORCE_START, STOP: the first running command ends the pre-stage, whose
        next command (the kick-off) would rule out any placement, and clears the game
        events, the placement position and the next command."""
        await self.send({"reset_match": True})
        await asyncio.sleep(0.5)
        self.seen.events.clear()
        await self.send({"change": {"updateConfigChange": {"division": "DIV_B",
                                                           "matchType": "FRIENDLY"}}})
        await self.send({"configDelta": {"autoContinue": self.a.auto_continue}})
        await self.play("match")
        await self.command("STOP")
        await self.command("FORCE_START")
        await asyncio.sleep(0.5)
        await self.command("STOP")

    async def referee_source(self) -> None:
        r = (await self.http.get("/api/referee")).json()
        active = r.get("active") or {}
        print(f"station referee: active source {active.get('source')} "
              f"({active.get('source_identifier')}), command {active.get('command')}; internal "
              f"enabled {r['internal']['enabled']}, foreign {r['internal']['foreign_source']}")

    async def ball_out(self) -> tuple[float, float]:
        """The ball beyond the +y touch line, then the event an autoref would send."""
        x, y = self.a.out_x, self.a.out_y
        await self.ball(x, y)
        await self.until(lambda: self.seen.truth is not None
                         and math.dist(self.seen.truth, (x, y)) < 0.01, 3, "ball teleported")
        await asyncio.sleep(0.5)
        await self.send({"change": {"addGameEventChange": {"gameEvent": {
            "type": "BALL_LEFT_FIELD_TOUCH_LINE",
            "ballLeftFieldTouchLine": {"byTeam": "YELLOW", "location": {"x": x, "y": 3.0}}}}}})
        ok = await self.until(lambda: self.seen.command() == "BALL_PLACEMENT BLUE", 10,
                              "GC command BALL_PLACEMENT BLUE")
        pos = self.seen.placement_pos()
        print(f"{self.seen.t():6.2f} placement pos {pos}, next command "
              f"{self.seen.match.get('nextCommand')}, started {ok}")
        assert pos is not None
        return pos

    async def sample(self, seconds: float, every: float, stop: Any = None) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end and not (stop and stop()):
            left = self.seen.match.get("currentActionTimeRemaining")
            print(f"{self.seen.t():6.2f} {self.seen.command()}, action time left {left}; "
                  f"{self.seen.balls()}")
            await asyncio.sleep(every)

    async def placement_timeout(self) -> None:
        await self.setup()
        await self.ball_out()
        await self.sample(40, 2.0, lambda: "PLACEMENT_FAILED" in self.seen.events)
        await self.until(lambda: "PLACEMENT_FAILED" in self.seen.events, 5,
                         "PLACEMENT_FAILED")
        await self.sample(10, 1.0, lambda: self.seen.command().startswith("DIRECT"))
        await self.sample(3, 1.0)

    async def placement_complete(self) -> None:
        await self.setup()
        pos = await self.ball_out()

        def resting_at_mark() -> bool:
            tr = self.seen.tracked
            return tr is not None and tr[2] < 0.05 and math.dist(pos, tr[:2]) < 0.05
        start = time.monotonic()
        await self.until(resting_at_mark, 28, "tracked ball resting within 5 cm of the mark")
        print(f"{self.seen.t():6.2f} ball at the mark {time.monotonic() - start:.1f} s after "
              f"the command; {self.seen.balls()}")
        await asyncio.sleep(self.a.settle)
        print(f"{self.seen.t():6.2f} operator: BALL_PLACEMENT_COMPLETE; {self.seen.balls()}")
        await self.send({"continueAction": {"type": "BALL_PLACEMENT_COMPLETE",
                                            "forTeam": "BLUE"}})
        await self.until(lambda: "PLACEMENT_SUCCEEDED" in self.seen.events, 5,
                         "PLACEMENT_SUCCEEDED")
        await self.sample(12, 0.5, lambda: self.seen.command().startswith("DIRECT"))
        await self.sample(3, 1.0)

    def blues(self) -> list[tuple[str, int, float, float, float]]:
        return [r for r in self.seen.truth_robots if r[0] == "blue"]

    async def stop_ready(self) -> None:
        await self.setup()
        await self.until(lambda: all(r[4] < 0.05 for r in self.blues()), 10,
                         "blue robots at rest in STOP")
        await asyncio.sleep(0.5)
        # the blue robot nearest the centre; the ball 0.15 m from its centre, towards the centre
        _, rid, x, y, _ = min(self.blues(), key=lambda r: math.hypot(r[2], r[3]))
        d = math.hypot(x, y) or 1.0
        await self.ball(x - 0.15 * x / d, y - 0.15 * y / d)
        seen_by_gc = next(((r[2], r[3]) for r in self.seen.tracked_robots
                           if r[0] == "blue" and r[1] == rid), None)
        print(f"{self.seen.t():6.2f} ball put 0.15 m from blue {rid} at ({x:.3f}, {y:.3f}) "
              f"(tracked {seen_by_gc}), robots at rest")
        t_put = time.monotonic()
        fastest = 0.0
        touch, kicks = self.seen.truth_touch, dict(self.seen.truth_kicks)

        def too_close() -> bool:  # this robot named (the attacker may be named already)
            return any("too close" in i and f"{rid} BLUE" in i
                       for a in self.seen.gc.get("continueActions") or []
                       for i in a.get("continuationIssues") or [])
        await self.until(too_close, 3, f"GC reports blue {rid} too close")
        t_seen = time.monotonic()
        async def watch_ball() -> None:
            nonlocal fastest
            await asyncio.sleep(0.3)  # the teleport itself
            while True:
                fastest = max(fastest, self.seen.truth_ball_speed)
                await asyncio.sleep(0.02)
        watcher = asyncio.create_task(watch_ball())
        await self.until(lambda: not too_close(), 15, "GC clears robots too close")
        t_clear = time.monotonic()
        ball = self.seen.truth or (0.0, 0.0)
        near = {team: min((math.dist(ball, r[2:4]) for r in self.seen.truth_robots
                           if r[0] == team), default=float("nan"))
                for team in ("blue", "yellow")}
        print(f"{self.seen.t():6.2f} 'too close' for blue {rid} seen {t_seen - t_put:.2f} s "
              f"after the teleport, cleared {t_clear - t_put:.2f} s after it; nearest robot "
              f"centre to the ball (truth): blue {near['blue']:.3f} m, yellow "
              f"{near['yellow']:.3f} m (the GC's limit: 0.5 + 0.09 - 0.05 = 0.54 m)")
        await self.sample(3, 1.0)
        watcher.cancel()
        kicked = {k: v for k, v in self.seen.truth_kicks.items() if kicks.get(k) != v}
        print(f"{self.seen.t():6.2f} fastest ball (truth) after the teleport: {fastest:.3f} m/s;"
              f" fieldsim's last touch {touch} before, {self.seen.truth_touch} after; kick "
              f"counts changed: {kicked or 'none'}")

    async def no_progress(self) -> None:
        await self.setup()
        await self.play("idle")
        try:
            await self.ball(self.a.out_x, 0.0)
            await asyncio.sleep(1.0)
            await self.command("FORCE_START")
            t = time.monotonic()
            await self.until(lambda: "NO_PROGRESS_IN_GAME" in self.seen.events
                             or self.seen.command() == "STOP", 20, "NO_PROGRESS_IN_GAME")
            print(f"{self.seen.t():6.2f} {time.monotonic() - t:.1f} s after FORCE_START: "
                  f"events {self.seen.events}; {self.seen.balls()}")
            await self.sample(3, 1.0)
        finally:
            await self.play("match")

    async def rest(self) -> None:
        """HALT (nothing moves), the ball at rest at each spot for --rest-s: how often the
        tracked ball the GC gets is over its 0.2 m/s "steady" threshold, which its placement
        and STOP checks read ("Ball position is not steady"; a placement is required)."""
        await self.command("HALT")
        for x, y in self.a.rest_spots:
            await self.ball(x, y)
            await asyncio.sleep(1.0)
            near = min(math.dist((x, y), r[2:4]) for r in self.seen.truth_robots)
            self.seen.quiet = True
            u0, f0, self.seen.unsteady_max = self.seen.unsteady, self.seen.frames, 0.0
            errs: list[float] = []
            end = time.monotonic() + self.a.rest_s
            while time.monotonic() < end:
                if self.seen.tracked and self.seen.truth:
                    errs.append(math.dist(self.seen.tracked[:2], self.seen.truth))
                await asyncio.sleep(0.05)
            self.seen.quiet = False
            n, u = self.seen.frames - f0, self.seen.unsteady - u0
            print(f"{self.seen.t():6.2f} ball at rest at ({x}, {y}), nearest robot {near:.2f} m:"
                  f" {u} of {n} tracked frames at >= 0.2 m/s (max {self.seen.unsteady_max:.2f})"
                  f"; tracked-truth distance max {max(errs) * 1000:.1f} mm")

    # --- the scenarios that place the other team (--sim-control-port) ---------------------

    def teleport(self, team: str, rid: int, x: float | None = None, y: float | None = None,
                 orientation: float | None = None, present: bool | None = None) -> None:
        """One robot through fieldsim's SimulatorCommand port (m, rad); present=False takes
        it off the field, present=True puts it (back) on."""
        if self.a.sim_control_port is None:
            raise SystemExit("this scenario needs --sim-control-port")
        cmd = control_pb.SimulatorCommand()
        t = cmd.control.teleport_robot.add()
        t.id.id = rid
        t.id.team = gc_common_pb.Team.BLUE if team == "blue" else gc_common_pb.Team.YELLOW
        for name, value in (("x", x), ("y", y), ("orientation", orientation),
                            ("present", present)):
            if value is not None:
                setattr(t, name, value)
        self.sim.sendto(cmd.SerializeToString(), ("127.0.0.1", self.a.sim_control_port))

    async def our_team(self) -> str:
        r = (await self.http.get("/api/params")).json()
        return str(r["values"]["team"]["our_team"])

    def team_state(self, team: str) -> dict[str, Any]:
        return dict((self.seen.match.get("teamState") or {}).get(team.upper()) or {})

    def robots_of(self, team: str) -> list[tuple[str, int, float, float, float]]:
        return [r for r in self.seen.truth_robots if r[0] == team]

    def action(self, kind: str) -> tuple[str | None, list[str]]:
        """State and readiness issues (the preparation countdown left out) of an action."""
        for a in self.seen.gc.get("continueActions") or []:
            if a.get("type") == kind:
                return a.get("state"), [i for i in a.get("continuationIssues") or []
                                        if PREPARATION not in i]
        return None, []

    def ready(self, kind: str = "NORMAL_START") -> bool:
        state, issues = self.action(kind)
        return state in ("WAITING", "READY_AUTO", "READY_MANUAL") and not issues

    def issue_with(self, text: str, kind: str = "NORMAL_START") -> bool:
        return any(text in i for i in self.action(kind)[1])

    async def prepare(self, kind: str, team: str, ball: tuple[float, float]) -> None:
        """From STOP (auto continue off): the ball at ``ball``, then the prepare command; how
        long until the GC has no readiness issue left and until it would continue."""
        await self.ball(*ball)
        await self.until(lambda: self.seen.truth is not None
                         and math.dist(self.seen.truth, ball) < 0.01, 3, "ball teleported")
        await asyncio.sleep(0.5)
        t = time.monotonic()
        await self.command(kind, team.upper())
        ok = await self.until(self.ready, 20, f"{kind} {team}: no readiness issue")
        t_ready = time.monotonic() - t
        await self.until(lambda: self.action("NORMAL_START")[0] == "READY_AUTO", 5,
                         "NORMAL_START READY_AUTO")
        print(f"{self.seen.t():6.2f} {kind} {team}: no readiness issue {t_ready:.2f} s after "
              f"the command ({'ready' if ok else 'NOT ready'}), NORMAL_START "
              f"{self.action('NORMAL_START')[0]} {time.monotonic() - t:.2f} s after it")
        if not ok:
            print(f"        issues left: {self.action('NORMAL_START')[1]}")
        moved = math.dist(ball, self.seen.truth) if self.seen.truth else float("nan")
        print(f"        the ball (truth) {moved:.3f} m from where it was put; fieldsim's last "
              f"touch {self.seen.truth_touch}")

    async def misplace(self, team: str, rid: int, to: tuple[float, float],
                       back: tuple[float, float] | None, text: str) -> None:
        """Robot ``rid`` of ``team`` teleported to ``to``: how soon the GC says ``text`` (at a
        penalty it names the second robot of the attackers in front of the ball, which need
        not be this one), and how soon that is gone: ours come back by themselves, the other
        team's robot is teleported to ``back`` after 3 s."""
        self.teleport(team, rid, *to)
        t = time.monotonic()
        seen = await self.until(lambda: self.issue_with(text), 3, f"GC: {text}")
        t_seen = time.monotonic() - t
        print(f"{self.seen.t():6.2f} {team} {rid} put at {to}: GC "
              f"{'says ' + repr(text) if seen else 'says nothing'} {t_seen:.2f} s later; "
              f"issues {self.action('NORMAL_START')[1]}")
        if back is not None:
            await asyncio.sleep(3.0)
            still = self.issue_with(text)
            print(f"{self.seen.t():6.2f} still named after 3 s: {still} ({team} {rid} tracked "
                  f"at {self.tracked_at(team, rid)}, truth {self.truth_at(team, rid)}); put "
                  f"back at {back}")
            self.teleport(team, rid, *back)
            t = time.monotonic()
        cleared = await self.until(lambda: not self.issue_with(text), 15, f"GC clears {text}")
        ready = await self.until(self.ready, 10, "no readiness issue")
        print(f"{self.seen.t():6.2f} cleared {time.monotonic() - t:.2f} s after "
              f"{'the put back' if back else 'the teleport'} ({cleared}), ready {ready}; "
              f"{team} {rid} truth {self.truth_at(team, rid)}, tracked "
              f"{self.tracked_at(team, rid)}")

    def truth_at(self, team: str, rid: int) -> tuple[float, float] | None:
        return next(((round(r[2], 3), round(r[3], 3)) for r in self.robots_of(team)
                     if r[1] == rid), None)

    def tracked_at(self, team: str, rid: int) -> tuple[float, float] | None:
        return next(((round(r[2], 3), round(r[3], 3)) for r in self.seen.tracked_robots
                     if r[0] == team and r[1] == rid), None)

    async def manual(self) -> None:
        """setup() with auto continue off, and the team nobody drives back in fieldsim's
        start formation on its half (a scenario before may have moved it)."""
        await self.setup()
        await self.send({"configDelta": {"autoContinue": False}})
        ours = await self.our_team()
        theirs = "yellow" if ours == "blue" else "blue"
        side = 1 if self.team_state(theirs).get("onPositiveHalf") else -1
        poses = formation(self.a.robots, side, division_geometry(self.a.division))
        for rid, (x, y, th) in enumerate(poses):
            self.teleport(theirs, rid, x, y, th, present=True)
        await asyncio.sleep(0.5)

    async def each_team(self, scenario: Callable[[str], Awaitable[None]]) -> None:
        """``scenario`` for each team asked for, then the GC's auto continue as it was."""
        for team in self.a.teams:
            await scenario(team)
        await self.send({"configDelta": {"autoContinue": self.a.auto_continue}})

    async def kickoff(self) -> None:
        await self.each_team(self.kickoff_for)

    async def kickoff_for(self, team: str) -> None:
        ours = await self.our_team()
        theirs = "yellow" if ours == "blue" else "blue"
        print(f"- kick-off for {team} (Touchline plays {ours})")
        await self.manual()
        await self.until(lambda: bool(self.team_state(ours)), 3, "team state")
        ours_pos = 1.0 if self.team_state(ours).get("onPositiveHalf") else -1.0
        await self.prepare("KICKOFF", team, (0.0, 0.0))
        # the other team's robot nearest the halfway line, into our half, outside the circle
        rid, x, y = min(((r[1], r[2], r[3]) for r in self.robots_of(theirs)),
                        key=lambda r: abs(r[1]))
        await self.misplace(theirs, rid, (ours_pos * 0.6, 0.9 if y >= 0 else -0.9),
                            (x, y), f"{rid} {theirs.upper()} is not in its own half")
        # ours: the one nearest the halfway line, just over it
        rid, _, y = min(((r[1], r[2], r[3]) for r in self.robots_of(ours)),
                        key=lambda r: abs(r[1]))
        await self.misplace(ours, rid, (-ours_pos * 0.6, 0.9 if y >= 0 else -0.9), None,
                            f"{rid} {ours.upper()} is not in its own half")

    async def penalty(self) -> None:
        await self.each_team(self.penalty_for)

    async def penalty_for(self, team: str) -> None:
        ours = await self.our_team()
        theirs = "yellow" if ours == "blue" else "blue"
        print(f"- penalty for {team} (Touchline plays {ours})")
        await self.manual()
        defending = "yellow" if team == "blue" else "blue"
        await self.until(lambda: bool(self.team_state(defending)), 3, "team state")
        side = 1.0 if self.team_state(defending).get("onPositiveHalf") else -1.0
        mark = (side * (self.a.half_length - self.a.penalty_mark_distance), 0.0)
        keeper = int(self.team_state(defending).get("goalkeeper", 0))
        others = sorted(r[1] for r in self.robots_of(theirs))
        behind = -side  # away from the goal attacked
        if theirs == defending:  # their keeper on its goal line, the rest 1 m behind
            self.teleport(theirs, keeper, side * (self.a.half_length - 0.05), 0.0,
                          math.pi if side > 0 else 0.0)
            rest = [r for r in others if r != keeper]
            x = mark[0] + behind * 1.8
        else:  # their kicker behind the ball, the rest 1 m behind it
            kicker, *rest = others
            self.teleport(theirs, kicker, mark[0] + behind * 0.2, 0.0,
                          0.0 if side > 0 else math.pi)
            x = mark[0] + behind * 1.8
        for k, rid in enumerate(rest):
            self.teleport(theirs, rid, x, (k - (len(rest) - 1) / 2) * 1.0)
        print(f"{self.seen.t():6.2f} mark {mark}, {defending} defends (keeper {keeper}); "
              f"{theirs} placed by teleport")
        await self.prepare("PENALTY", team, mark)
        if ours != defending:  # one of ours (not the kicker) in front of the ball
            rid = max((r for r in self.robots_of(ours)
                       if math.dist(r[2:4], mark) > 0.4),
                      key=lambda r: side * r[2])[1]
            await self.misplace(ours, rid, (mark[0] + side * 0.6, 1.2), None,
                                f"{ours.upper()} does not keep required distance")
        else:  # our keeper out of the goal, then a robot of ours in front of the ball
            await self.misplace(ours, keeper, (side * (self.a.half_length - 0.6), 0.4), None,
                                "Keeper is not inside goal")
            rid = next(r[1] for r in self.robots_of(ours) if r[1] != keeper)
            await self.misplace(ours, rid, (mark[0] + side * 0.6, 1.2), None,
                                f"{ours.upper()} does not keep required distance")

    async def robot_count(self) -> None:
        await self.each_team(self.card_for)

    async def card_for(self, team: str) -> None:
        ours = await self.our_team()
        print(f"- yellow card for {team} (Touchline plays {ours})")
        await self.manual()
        await self.ball(0.0, -1.0)  # away from both teams
        await asyncio.sleep(1.0)
        n0 = len(self.robots_of(team))
        tracked0 = sum(1 for r in self.seen.tracked_robots if r[0] == team)
        allowed0 = self.team_state(team).get("maxAllowedBots")
        text = f"{team.capitalize()} team has too many robots"
        kind = "FORCE_START"
        print(f"{self.seen.t():6.2f} {team}: {n0} robots (truth), {tracked0} tracked, "
              f"allowed {allowed0}; issues {self.action(kind)[1]}")
        t = time.monotonic()
        await self.send({"change": {"addYellowCardChange": {"forTeam": team.upper()}}})
        await self.until(lambda: self.team_state(team).get("maxAllowedBots") != allowed0,
                         3, "max allowed robots down")
        flagged = await self.until(lambda: self.issue_with(text, kind), 3, text)
        allowed = self.team_state(team).get("maxAllowedBots")
        print(f"{self.seen.t():6.2f} card: allowed {allowed}, GC "
              f"{'flags' if flagged else 'does NOT flag'} {text!r} "
              f"{time.monotonic() - t:.2f} s after the card")
        if team == ours:  # the robot Touchline sends off: near the halfway line, at rest
            def parked() -> list[tuple[str, int, float, float, float]]:
                return [r for r in self.robots_of(team) if abs(r[2]) < 1.0
                        and abs(r[3]) > self.a.half_width - 0.6 and r[4] < 0.05]
            await self.until(lambda: bool(parked()), 20, "a robot parked for the handler")
            t_parked = time.monotonic() - t
            rid = parked()[0][1] if parked() else max(self.robots_of(team),
                                                       key=lambda r: abs(r[3]))[1]
            still = self.issue_with(text, kind)
            print(f"{self.seen.t():6.2f} {team} {rid} parked at the halfway line "
                  f"{t_parked:.2f} s after the card; GC still flags it: {still}")
        else:
            rid = max(r[1] for r in self.robots_of(team))
        self.teleport(team, rid, present=False)
        t = time.monotonic()
        gone = await self.until(lambda: all(r[1] != rid or r[0] != team
                                            for r in self.seen.tracked_robots), 5,
                                "robot gone from the tracked frames")
        t_gone = time.monotonic() - t
        cleared = await self.until(lambda: not self.issue_with(text, kind), 5,
                                   f"GC clears {text}")
        print(f"{self.seen.t():6.2f} {team} {rid} taken off fieldsim: gone from the tracked "
              f"frames {t_gone:.2f} s later ({gone}), the GC's issue gone "
              f"{time.monotonic() - t:.2f} s later ({cleared}); issues "
              f"{self.action(kind)[1]}")
        self.teleport(team, rid, -1.0 if team == "blue" else 1.0,
                      -(self.a.half_width - 0.3), present=True)
        t = time.monotonic()
        back = await self.until(lambda: self.issue_with(text, kind), 5, text)
        print(f"{self.seen.t():6.2f} {team} {rid} back on the field: flagged again "
              f"{time.monotonic() - t:.2f} s later ({back})")

    async def card_running(self) -> None:
        """A yellow card for us in a running game (FORCE_START, the match play): the GC counts
        after the card's 10 s removal time, every tick, and files TOO_MANY_ROBOTS while our
        team has more robots in the frames than allowed. The robot Touchline sends to the
        halfway line is taken off fieldsim ``--lift-after`` s after the card (the handler)."""
        ours = await self.our_team()
        await self.manual()
        await self.send({"configDelta": {"autoContinue": self.a.auto_continue}})
        await self.ball(0.0, -1.0)
        await asyncio.sleep(1.0)
        self.seen.events.clear()
        await self.command("FORCE_START")
        await asyncio.sleep(1.0)
        t = time.monotonic()
        await self.send({"change": {"addYellowCardChange": {"forTeam": ours.upper()}}})
        print(f"{self.seen.t():6.2f} yellow card for {ours} in a running game; lift after "
              f"{self.a.lift_after} s")

        def leaving() -> list[tuple[str, int, float, float, float]]:
            return [r for r in self.robots_of(ours) if abs(r[2]) < 1.0
                    and abs(r[3]) > self.a.half_width - 0.6]
        await self.until(lambda: bool(leaving()), self.a.lift_after, "a robot at the halfway line")
        left = max(0.0, self.a.lift_after - (time.monotonic() - t))
        await asyncio.sleep(left)
        rid = leaving()[0][1] if leaving() else max(self.robots_of(ours),
                                                    key=lambda r: abs(r[3]))[1]
        self.teleport(ours, rid, present=False)
        t_lift = time.monotonic() - t
        print(f"{self.seen.t():6.2f} {ours} {rid} taken off {t_lift:.2f} s after the card")
        await self.until(lambda: "TOO_MANY_ROBOTS" in self.seen.events, 15 - t_lift,
                         "TOO_MANY_ROBOTS")
        gone = "TOO_MANY_ROBOTS" in self.seen.events
        print(f"{self.seen.t():6.2f} TOO_MANY_ROBOTS {'filed' if gone else 'not filed'} "
              f"({time.monotonic() - t:.2f} s after the card); events {self.seen.events}")
        await self.command("STOP")
        self.teleport(ours, rid, 0.0, -(self.a.half_width - 0.3), present=True)


async def run(a: argparse.Namespace) -> None:
    seen = Seen()
    tasks = [asyncio.create_task(tracked_reader(seen, a.group, a.tracker_port)),
             asyncio.create_task(truth_reader(seen, a.truth))]
    async with websockets.connect(f"ws://{a.gc}/api/control",
                                  close_timeout=CLOSE_TIMEOUT_S) as ws:
        tasks.append(asyncio.create_task(gc_reader(ws, seen)))
        check = Check(a, ws, seen)
        await check.until(lambda: bool(seen.match) and seen.tracked is not None
                          and seen.truth is not None, 5, "GC state, tracked frames, truth")
        trackers = seen.gc.get("trackers")
        print(f"GC trackers {trackers}")
        await check.referee_source()
        for name in a.scenario:
            print(f"--- {name}")
            await getattr(check, name.replace("-", "_"))()
        await check.send({"change": {"newCommandChange": {"command": {"type": "HALT",
                                                                      "forTeam": "UNKNOWN"}}}})
        await check.http.aclose()
        check.sim.close()
    for task in tasks:
        task.cancel()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--gc", required=True, help="the game controller's HOST:PORT")
    p.add_argument("--station", required=True, help="the station's HOST:PORT")
    p.add_argument("--group", default="224.5.23.2")
    p.add_argument("--tracker-port", type=int, required=True)
    p.add_argument("--truth", required=True, help="fieldsim's --truth-pub endpoint")
    p.add_argument("--out-x", type=float, default=1.5, help="where the ball goes out (m)")
    p.add_argument("--out-y", type=float, default=3.15, help="beyond the touch line at 3 m")
    p.add_argument("--settle", type=float, default=1.0,
                   help="seconds between the ball resting at the mark and 'complete'")
    p.add_argument("--rest-s", type=float, default=30.0, help="seconds per spot in 'rest'")
    p.add_argument("--rest-spot", dest="rest_spots", action="append",
                   type=lambda v: tuple(float(c) for c in v.split(",")),
                   help="X,Y (m) for 'rest' (repeatable; default 1.5,0 -2,-2.2 0,1)")
    p.add_argument("--no-auto-continue", dest="auto_continue", action="store_false")
    p.add_argument("--sim-control-port", type=int, default=None,
                   help="fieldsim's simulation control port (kickoff, penalty, robot-count)")
    p.add_argument("--team", dest="teams", action="append", choices=["blue", "yellow"],
                   help="whose kick-off / penalty / card (repeatable; default both)")
    p.add_argument("--lift-after", type=float, default=5.0,
                   help="card-running: s between the card and the robot taken off")
    p.add_argument("--division", default="B", choices=["A", "B"], help="fieldsim's field")
    p.add_argument("--robots", type=int, default=6, help="per team in fieldsim")
    p.add_argument("--penalty-mark-distance", type=float, default=None,
                   help="from the goal centre, m (default: the division's, as fieldsim "
                        "sends it to the GC)")
    p.add_argument("scenario", nargs="+", choices=["placement-timeout", "placement-complete",
                                                   "stop-ready", "no-progress", "rest",
                                                   "kickoff", "penalty", "robot-count",
                                                   "card-running"])
    a = p.parse_args()
    a.rest_spots = a.rest_spots or [(1.5, 0.0), (-2.0, -2.2), (0.0, 1.0)]
    a.teams = a.teams or ["blue", "yellow"]
    field = division_geometry(a.division)
    a.half_length, a.half_width = field.half_length / 1000.0, field.half_width / 1000.0
    if a.penalty_mark_distance is None:
        a.penalty_mark_distance = field.penalty_mark_distance / 1000.0
    asyncio.run(run(a))


if __name__ == "__main__":
    main()
