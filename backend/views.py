"""The browser's data, built on the station thread from the parts it is given (``ViewParts``:
every processor, topic and store it reads, named once): the world message, health, and the
referee and strategy views (their shapes are in ``contract.py``; the e-stop's and the
arming's come from ``backend/safety.py``). The station publishes them (``Station.views``,
through ``backend/viewhub.py``) or answers with them when asked (``Station.browser``)."""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

from google.protobuf.message import DecodeError

from sslnet.proc import CpuMeter, rss_mb
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket

from . import contract, topics
from .bus import DataBus, Topic
from .engine.switch import EngineSwitch
from .evaluation import Evaluation
from .messages import TargetEntry
from .operators import Operators
from .params.model import PLAYS
from .params.store import ParamStore
from .processor import Every, OnTopic, Runner
from .processors import (
    CommandPublisher,
    ControlProcessor,
    FeedbackProcessor,
    InternalRefereeProcessor,
    RefereeIngest,
    RelayIngest,
    StrategyProcessor,
    VisionIngest,
    WorldProcessor,
)
from .processors.publisher import FRAME_AGE_STAGE
from .recording import RecordingControl
from .referee.internal import OPERATOR_COMMANDS, InternalReferee
from .referee.watch import RefereeWatch
from .replay.control import ReplayControl
from .safety import RELAY_STATS_FRESH_S, Safety
from .startup import StartupTimeline
from .strategy.plays import PLAY_INFO
from .teamcode.processors import TeamProcessors
from .teamcode.registry import TeamRegistry
from .viewhub import WebStats
from .world.feedback import RobotFeedbackView
from .world.referee import RefereeState
from .world.state import KickedBall, Team, WorldState


@dataclass(frozen=True)
class ViewParts:
    """What the browser's data is built from: the parts ``station.py`` made, each named once
    (the views read these and nothing else)."""

    params: ParamStore
    bus: DataBus
    runner: Runner
    safety: Safety
    ingest: RelayIngest
    vision: VisionIngest
    referee: RefereeIngest
    world: WorldProcessor
    feedback: FeedbackProcessor
    strategy: StrategyProcessor
    control: ControlProcessor
    publisher: CommandPublisher
    internal_referee: InternalRefereeProcessor
    referee_state: InternalReferee
    referee_watch: RefereeWatch
    team: TeamRegistry
    team_processors: TeamProcessors
    engine: EngineSwitch
    replay: ReplayControl
    recording: RecordingControl
    operators: Operators
    startup: StartupTimeline
    web: WebStats
    cpu: CpuMeter
    #: the state folder (the launcher's supervisor.json), None for a station without one
    state_dir: Path | None
    started_mono: float
    #: the Evaluate tab's job (its progress in every health message)
    evaluation: Evaluation

    @property
    def world_topic(self) -> Topic[WorldState]:
        return self.bus.of(topics.WORLD)

    @property
    def targets_topic(self) -> Topic[dict[Any, Any]]:
        return self.bus.of(topics.TARGETS)

    @property
    def referee_topic(self) -> Topic[RefereeState]:
        return self.bus.of(topics.REFEREE)

    @property
    def geometry_topic(self) -> Topic[dict[str, Any]]:
        return self.bus.of(topics.GEOMETRY)

    @property
    def relay_stats(self) -> Topic[dict[str, Any]]:
        return self.bus.of(topics.RELAY_STATS)


class BrowserData:
    """The browser's data of one station, each built when called (on the station thread):
    what the routes answer with and what ``ViewHub`` publishes."""

    def __init__(self, parts: ViewParts) -> None:
        self.parts = parts

    def world(self) -> contract.World:
        return world(self.parts)

    def health(self) -> contract.Health:
        return health(self.parts)

    def referee(self) -> contract.RefereeView:
        return referee_view(self.parts)

    def strategy_state(self) -> contract.StrategyState:
        return strategy_state(self.parts)

    def strategy(self) -> contract.StrategyView:
        return strategy_view(self.parts)

    def geometry(self) -> contract.Geometry | None:
        """The field as decoded (cleaned at decode time; non-finite numbers, should any get
        through, become null here rather than break the JSON)."""
        g = self.parts.geometry_topic.latest_value()
        return None if g is None else cast(contract.Geometry, g)

    def geometry_seq(self) -> int:
        return self.parts.geometry_topic.seq

    def world_version(self) -> tuple[object, ...]:
        """Changes whenever the world message would: a new world, a referee message, the
        e-stop, why the robots are stopped (that changes while no world is written: vision
        lost), or the internal referee (its panel follows the world message)."""
        p = self.parts
        ir, rs, safety = p.internal_referee, p.referee_state, p.safety
        return (p.world_topic.seq, p.referee_topic.seq, safety.estop, p.replay.player.serial,
                safety.armed, safety.arming_required,
                p.control.halt_reason, rs.command_counter,
                ir.enabled, ir.foreign_active(), rs.max_allowed_bots("blue"),
                rs.max_allowed_bots("yellow"), rs.blue.score, rs.yellow.score)


def engine_health(p: ViewParts) -> contract.EngineHealth | None:
    sp = p.strategy.params
    if sp.engine == "off":
        return None
    eng = p.strategy.engine
    out: dict[str, Any] = dict(eng.health()) if eng is not None else {
        "kind": sp.engine, "workers": 0, "busy": 0, "idle": 0, "calls": 0,
        "calls_per_s": 0.0, "latency_mean_ms": 0.0, "latency_p99_ms": 0.0, "ok": 0,
        "errors": 0, "timeouts": 0, "crashes": 0, "restarts": 0, "start_failures": 0,
        "last_error": p.engine.error or "starting"}
    out["function"] = sp.goalkeeper_function
    out["fallbacks"] = p.strategy.engine_fallbacks
    out["running"] = eng is not None
    if not out.get("last_error") and p.strategy.engine_last_error:
        out["last_error"] = p.strategy.engine_last_error
    return cast(contract.EngineHealth, out)


def strategy_state(p: ViewParts) -> contract.StrategyState:
    """What the strategy is doing now (sent with every world update: kept small)."""
    core = p.strategy.core
    sit = core.situation if core is not None else None
    return {
        "play": p.params.current.strategy.play,
        "situation": sit.key if sit is not None else "running",
        "situation_text": sit.text() if sit is not None else "",
        "our_team": p.params.current.team.our_team,
        "our_side": "negative-x" if core is None or core.frame.sign > 0 else "positive-x",
        "side_from_referee": bool(core and core.side_from_referee),
        "tick_ms": core.last_tick_ms if core is not None else 0.0,
        "robot_plays": {str(rid): play for rid, play in p.strategy.robot_plays.items()},
        "stopped": [{"id": rid, "play": play, "reason": why}
                    for rid, play, why in p.strategy.stopped],
    }


def strategy_view(p: ViewParts) -> contract.StrategyView:
    """``strategy_state`` plus the plays to choose from and the roles (GET /api/strategy)."""
    core = p.strategy.core
    team = p.params.current.team.our_team
    plays: list[contract.PlayInfo] = [
        {"name": n, "title": PLAY_INFO[n][0], "description": PLAY_INFO[n][1],
         "source": "builtin", "file": None, "language": None} for n in PLAYS]
    plays += [{"name": n, "title": f.title or n, "description": f.description,
               "source": "team", "file": f.name, "language": f.language}
              for n, f in sorted(p.team.plays().items())]
    return {
        **strategy_state(p),
        "plays": plays,
        "roles": {f"{team}/{rid}": role
                  # a copy: the strategy's worker thread may be assigning roles now
                  for rid, role in (core.roles.items() if core else [])},
    }


def referee_view(p: ViewParts) -> contract.RefereeView:
    ir = p.internal_referee
    state = p.referee_state
    return {
        "internal": {
            "enabled": ir.enabled,
            "disabled_reason": ir.disabled_reason,
            "foreign_source": ir.foreign_active(),
            "command": state.command,
            "stage": state.stage,
            "command_counter": state.command_counter,
            "designated_position": None if state.designated_position is None else {
                "x": state.designated_position[0], "y": state.designated_position[1]},
            "score": {"blue": state.blue.score, "yellow": state.yellow.score},
            "max_allowed_bots": {"blue": state.max_allowed_bots("blue"),
                                 "yellow": state.max_allowed_bots("yellow")},
            "commands": list(OPERATOR_COMMANDS),
        },
    }


def kick_view(k: KickedBall | None, t_ref: float) -> contract.BallKick | None:
    if k is None:
        return None
    return {
        "robot": None if k.robot is None else {"team": k.robot[0], "id": k.robot[1]},
        "start_x": k.start_x, "start_y": k.start_y, "start_t": k.start_t,
        "vx": k.vx, "vy": k.vy, "speed_mps": k.speed / 1000.0,
        "stop_x": k.stop_x, "stop_y": k.stop_y, "stop_t": k.stop_t,
        "stop_in_s": k.stop_t - t_ref,
        "chip": k.chip, "vz": k.vz, "land_x": k.land_x, "land_y": k.land_y, "land_t": k.land_t,
    }


def recorded_world(payload: bytes, commands: list[contract.RecordedCommand] | None = None
                   ) -> contract.RecordedWorld | None:
    """A tracked-vision record of the log (m) as the page draws it (mm), with the commands
    the log sent at that time."""
    commands = commands or []
    empty: contract.RecordedWorld | None = \
        {"source": "", "ball": None, "robots": [], "commands": commands} if commands else None
    if not payload:
        return empty
    p = TrackerWrapperPacket()
    try:
        p.ParseFromString(payload)
    except DecodeError:
        return empty
    f = p.tracked_frame
    ball: contract.Vec | None = None
    if f.balls:
        ball = {"x": f.balls[0].pos.x * 1000.0, "y": f.balls[0].pos.y * 1000.0}
    robots: list[contract.RawRobot] = [
        {"team": "yellow" if r.robot_id.team == 1 else "blue", "id": r.robot_id.id,
         "x": r.pos.x * 1000.0, "y": r.pos.y * 1000.0, "orientation": r.orientation}
        for r in f.robots if r.visibility > 0]
    return {"source": p.source_name, "ball": ball, "robots": robots, "commands": commands}


def feedback_view(v: RobotFeedbackView | None) -> contract.RobotFeedback | None:
    if v is None:
        return None
    return {
        "transport": v.transport, "ball_contact": v.ball_contact, "age_s": v.age_s,
        "no_answer": v.no_answer, "last_kick": v.last_kick,
        "last_kick_age_s": v.last_kick_age_s, "round_trip_ms": v.round_trip_ms,
        "commands_sent": v.commands_sent, "answers": v.answers, "loss": v.loss,
        "battery_v": v.battery_v, "kicker_v": v.kicker_v,
    }


def world(p: ViewParts) -> contract.World:
    world = p.world_topic.latest_value()
    targets: dict[tuple[Team, int], TargetEntry] = p.targets_topic.latest_value() or {}
    ref = p.referee_topic.latest()
    if ref is not None and p.control.active_referee() is None:
        ref = None  # the internal referee's own state after it was switched off
    commands = p.control.last_commands
    feedback = p.feedback.out.latest_value() or {}
    telemetry = p.control.telemetry
    player = p.replay.player
    now_unix = player.now_ns() / 1e9  # the log's time in replay
    out: contract.World = {
        "seq": p.world_topic.seq,
        "t_capture": world.t_capture if world else 0.0,
        "ball": None,
        "other_balls": [],
        "robots": [],
        "cameras": [],
        "referee": None,
        "estop": p.safety.estop,
        "estop_info": p.safety.estop_view(),
        "armed": p.safety.armed,
        "arming_required": p.safety.arming_required,
        "arming": p.safety.arming_view(),
        "halt_reason": p.control.halt_reason,
        "strategy": None,
        "internal_referee": referee_view(p)["internal"],
        "replay": player.clock(),
        "recorded": recorded_world(p.replay.recorded_tracked, p.replay.commands_view())
        if player.log is not None else None,
        "team": p.team_processors.world_view(),
    }
    out["strategy"] = strategy_state(p)
    if ref is not None:
        internal = ref.value.source_identifier == p.referee_state.source_identifier
        out["referee"] = ref.value.to_dict(time.monotonic() - ref.time_mono,
                                           "internal" if internal else None)
    if world is None:
        return out
    t_ref = world.t_capture
    if world.ball is not None:
        b = world.ball
        ball: contract.Ball = {
            "x": b.x, "y": b.y, "vx": b.vx, "vy": b.vy, "visible": b.visible,
            "age_s": t_ref - b.t_seen, "cameras": list(b.cameras), "raw_x": b.raw_x,
            "raw_y": b.raw_y, "predicted": b.predicted, "lost": b.lost, "filter": b.filter,
            "kick": kick_view(world.kicked_ball, t_ref), "z": b.z, "vz": b.vz,
            "flying": b.flying}
        out["ball"] = ball
    out["other_balls"] = [
        {"x": o.x, "y": o.y, "age_s": t_ref - o.t_seen, "cameras": list(o.cameras),
         "detections": o.detections} for o in world.other_balls]
    robots: list[contract.Robot] = []
    for r in world.robots:
        entry = targets.get((r.team, r.id))
        cmd = commands.get((r.team, r.id))
        robots.append({
            "team": r.team, "id": r.id, "x": r.x, "y": r.y, "orientation": r.orientation,
            "vx": r.vx, "vy": r.vy, "omega": r.omega, "visible": r.visible,
            "age_s": t_ref - r.t_seen, "cameras": list(r.cameras),
            "target": None if entry is None else {
                "x": entry.target.x, "y": entry.target.y,
                "orientation": entry.target.orientation, "source": entry.source,
            },
            "role": entry.role if entry is not None and entry.role else None,
            "path": None if entry is None or not entry.path else [
                {"x": px, "y": py} for px, py in entry.path],
            "kick": None if entry is None or entry.kick_speed_mps <= 0 else {
                "speed_mps": entry.kick_speed_mps, "chip": entry.chip},
            "dribbler": bool(entry is not None and entry.dribbler_rpm > 0),
            "controlled": entry is not None,
            "raw_x": r.raw_x, "raw_y": r.raw_y, "raw_orientation": r.raw_orientation,
            "predicted": r.predicted, "lost": r.lost, "filter": r.filter,
            "control": (cast(contract.RobotControl, telemetry.get(f"{r.team}/{r.id}"))
                        if entry is not None else None),
            "command": None if cmd is None else {
                "forward_mps": cmd.velocity.forward_mps,
                "left_mps": cmd.velocity.left_mps,
                "angular_radps": cmd.velocity.angular_radps,
            },
            "feedback": feedback_view(feedback.get((r.team, r.id))),
        })
    out["robots"] = robots
    out["cameras"] = [{
        "camera_id": c.camera_id, "frame_number": c.frame_number, "t_capture": c.t_capture,
        "age_s": now_unix - c.t_capture,
        "balls": [{"x": b.x, "y": b.y} for b in c.balls],
        "robots": [{"team": rr.team, "id": rr.id, "x": rr.x, "y": rr.y,
                    "orientation": rr.orientation} for rr in c.robots],
    } for c in world.cameras]
    return out


def world_health(p: ViewParts) -> contract.WorldHealth | None:
    """The world model's view: its age by the receive clock, what it dropped and why,
    each camera's clock offset."""
    model = p.world.model
    age = p.control.vision_age_s(time.monotonic())
    silence, lost = p.world.silence, p.control.vision_lost
    return {
        "age_s": age if math.isfinite(age) else None,
        "stale": age > p.control.vision_stale_s or lost is not None,
        "rejected": dict(model.rejected),
        "recent_rejections": p.world.recent_rejections(),
        "last_rejection": model.last_rejection,
        "clock_resyncs": model.clocks.resyncs,
        "camera_clock_offsets_s": {str(c): o for c, o in model.clocks.offsets().items()},
        "camera_pairs": cast(list[contract.CameraPair], model.camera_pairs.view()),
        "camera_rates_hz": {str(c): r for c, r in silence.rates_hz().items()},
        "lost_after_s": silence.lost_after_s(),
        "vision_lost": None if lost is None else lost.reason(),
    }


def latency_stages(p: ViewParts) -> list[contract.LatencyStage]:
    """Each stage from a vision datagram's arrival at the relay, in pipeline order."""
    stages = [cast(contract.LatencyStage, {"stage": name, **stage.summary()})
              for name, stage in (("decoded (vision ingest)", p.vision.latency),
                                  ("world model written", p.world.latency),
                                  ("commands sent to relay", p.publisher.latency),
                                  (FRAME_AGE_STAGE, p.publisher.frame_age))]
    rs = p.relay_stats.latest_value()
    if rs is not None and rs.get("command_latency_ms", -1) >= 0:
        # the relay's own p50 / p99 (vision arrival -> the first datagram of the commands it
        # caused, its last second; -1: none), beside its mean
        p50, p99 = rs.get("command_latency_p50_ms", -1), rs.get("command_latency_p99_ms", -1)
        stages.append({"stage": "sent to robots (relay)", "mean_ms": rs["command_latency_ms"],
                       "p50_ms": p50 if p50 >= 0 else None, "p99_ms": p99 if p99 >= 0 else None,
                       "n": None})
    return stages


def health(p: ViewParts) -> contract.Health:
    procs: list[contract.ProcessorHealth] = []
    for proc in p.runner.processors:
        trig = proc.trigger
        timing = proc.stats.summary()
        procs.append({
            "name": proc.name,
            "trigger": ("rate" if isinstance(trig, Every) else
                        f"topic:{trig.topic.name}" if isinstance(trig, OnTopic) else "source"),
            "configured_hz": trig.hz if isinstance(trig, Every) else None,
            "measured_hz": timing["measured_hz"], "tick_mean_ms": timing["tick_mean_ms"],
            "tick_p99_ms": timing["tick_p99_ms"],
            "overruns": proc.stats.overruns,
            "runs": proc.stats.rate.total,
            "errors": proc.stats.errors,
            "last_error": proc.stats.last_error,
        })
    topics: list[contract.TopicHealth] = [
        {"name": t.name, "size": len(t), "capacity": t.capacity, "seq": t.seq,
         "age_s": t.age_s()} for t in p.bus.topics()]
    streams: dict[str, Any] = {}
    vis = p.vision.counter.to_dict()
    # what the world model dropped, by the same reasons ("time out of range", ...)
    for reason, n in p.world.model.rejected.items():
        vis["errors_by_reason"][reason] = vis["errors_by_reason"].get(reason, 0) + n
        vis["errors"] += n
    streams["vision"] = vis
    streams["referee"] = p.referee.counter.to_dict()
    streams["zmq"] = p.ingest.counters["zmq"].to_dict()
    streams["feedback"] = p.feedback.counter.to_dict()
    relay = None
    rs = p.relay_stats.latest_value()
    if rs is not None:
        age = time.monotonic() - rs["received_mono"]
        relay = {k: v for k, v in rs.items()
                 if k not in ("streams", "received_mono", "cpu_percent", "rss_mb")}
        relay["alive"] = age < RELAY_STATS_FRESH_S
        relay["age_s"] = age
        for name, stream in rs["streams"].items():
            streams[f"relay.{name}"] = stream
    vision = streams.get("vision", {})
    # ok: the loop works (fresh vision, relay alive). A silent referee leaves it true: the
    # station then does what the rules expect of a team (it keeps obeying the last
    # command); it is a warning about a system outside the station, in `warnings`.
    replaying = p.replay.player.log is not None
    world = world_health(p)
    if replaying:
        # the vision is the log's, on the log's clock: a paused replay is not vision lost
        ok = relay is not None and relay["alive"]
    else:
        ok = bool(vision) and 0 <= vision.get("last_age_s", -1) < 1.0 and \
            relay is not None and relay["alive"]
        if world is not None and world["stale"]:
            ok = False
    referee = p.referee_watch.status()
    if referee is not None:
        referee["source"] = ("internal" if referee["source_identifier"]
                             == p.referee_state.source_identifier else "game-controller")
    recording = p.recording.status()
    sup = supervised(p)
    station_lines: list[str] = [
        f"{c['name']} restarted {c['restarts']} time{'s' if c['restarts'] > 1 else ''} by the "
        f"launcher (last exit {c['last_exit']}, up {c['up_s']:.0f} s)"
        for c in sup or [] if c["restarts"]]
    if recording["error"]:
        station_lines.append(f"recording stopped: {recording['error']}")
    if p.replay.player.log is not None:
        station_lines.append(f"replaying {p.replay.player.log.path}: nothing is sent to robots or "
                             "a simulator")
    access = p.web.access()
    if access["blocked_clients"]:
        station_lines.append(f"{access['blocked_clients']} address(es) refused for too many "
                             "wrong tokens (someone is guessing the operator token)")
    team_files = p.team.files_view()
    # a team file that failed while running (its robots are stopped, its topic stale)
    station_lines += [f"team code {f['name']}: {f['error']['kind']} at {f['error']['file']}"
                      f"{':' + str(f['error']['line']) if f['error']['line'] else ''}"
                      for f in team_files if f["state"] == "error" and f["error"] is not None
                      and p.team.runs.get(f["name"]) is not None
                      and p.team.runs[f["name"]].state == "error"]
    out: contract.Health = {
        "ok": ok,
        "warnings": [*p.safety.warnings(), *station_lines,
                     *_warnings(vision, relay, referee, world, replaying),
                     *p.params.warnings],
        "estop": p.safety.estop_view(),
        "arming": p.safety.arming_view(),
        "world": world,
        "referee": cast(contract.RefereeHealth | None, referee),
        "uptime_s": time.monotonic() - p.started_mono,
        "streams": streams,
        "processors": procs,
        "topics": topics,
        "relay": cast(contract.RelayHealth | None, relay),
        "latency": cast(contract.LatencyHealth, p.publisher.latency_summary()),
        "latency_stages": latency_stages(p),
        "websocket_clients": p.web.clients,
        "websocket_dropped": p.web.dropped,
        "engine": engine_health(p),
        "recording": recording,
        "processes": processes(p, rs),
        "access": access,
        "operators": p.operators.sessions(),
        "driving": p.operators.driving(),
        "operator_actions": p.operators.actions()[:20],
        "supervisor": sup,
        "startup": cast(contract.StartupInfo, p.startup.view()),
        "team_code": team_files,
        "evaluation": p.evaluation.job(),
    }
    return out


def supervised(p: ViewParts) -> list[contract.SupervisedProcess] | None:
    """The launcher's children and their restarts (``supervisor.json`` in the state folder,
    written by the launcher at every start and restart); None without a launcher."""
    if p.state_dir is None:
        return None
    try:
        raw = json.loads((p.state_dir / "supervisor.json").read_text())
        now = time.time()
        return [{"name": str(c["name"]), "pid": c.get("pid"), "restarts": int(c["restarts"]),
                 "last_exit": c.get("last_exit"),
                 "up_s": max(0.0, now - float(c["started_unix"]))} for c in raw["children"]]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def processes(p: ViewParts, relay_stats: dict[str, Any] | None) -> list[contract.ProcessHealth]:
    out: list[contract.ProcessHealth] = [
        {"name": "backend", "cpu_percent": p.cpu.read(), "rss_mb": rss_mb()}]
    if relay_stats is not None:
        out.append({"name": "relay", "cpu_percent": float(relay_stats.get("cpu_percent", 0.0)),
                    "rss_mb": float(relay_stats.get("rss_mb", 0.0))})
    return out


def _warnings(vision: dict[str, Any], relay: dict[str, Any] | None,
              referee: dict[str, Any] | None,
              world: contract.WorldHealth | None = None, replaying: bool = False) -> list[str]:
    """One line per problem: why ``ok`` is false, and a silent referee. In replay the vision
    is the log's: its pauses and gaps are no problem of the station's."""
    out: list[str] = []
    if replaying:
        vision, world = {"last_age_s": 0.0}, None
    if world is not None:
        if world["vision_lost"] is not None:
            out.append(f"{world['vision_lost']}: robots stopped")
        elif world["stale"] and vision.get("last_age_s", -1) >= 0 \
                and vision.get("last_age_s", -1) < 1.0:
            # vision arrives but nothing of it reaches the world: say why
            since = ("no frame merged yet" if world["age_s"] is None
                     else f"world not updated for {world['age_s']:.1f} s")
            out.append(f"{since} although vision arrives: robots stopped "
                       f"({world['last_rejection'] or 'no detection frame merged'})")
        if world["recent_rejections"]:
            out.append("vision dropped by the world model in the last 10 s: "
                       + ", ".join(f"{k} {v}" for k, v in world["recent_rejections"].items()))
    age = vision.get("last_age_s", -1)
    if not vision or age < 0:
        out.append("no vision received")
    elif age >= 1.0:
        out.append(f"no vision for {age:.1f} s")
    if relay is None:
        out.append("no relay statistics received")
    elif not relay["alive"]:
        out.append(f"relay silent for {relay['age_s']:.1f} s")
    line = RefereeWatch.warning(referee)
    if line is not None:
        out.append(line)
    return out
