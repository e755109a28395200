"""Decode simulator command datagrams into World calls and build the responses.

Pure (no sockets): ``CommandHandler.robot_control(team, data) -> reply bytes``,
``simulator_command(data) -> reply bytes``, ``grsim_packet(data) -> team | None``,
``grsim_status(team) -> Robots_Status bytes | None`` (on a change). Malformed input
(garbage, missing required fields: the Python runtime does not enforce ``required``, so
``IsInitialized()`` is checked) is counted, logged rate-limited and answered with an error
where the protocol has a response. Non-finite numbers are rejected and the robot stops.
"""

from __future__ import annotations

import logging
import math
from collections import Counter
from dataclasses import dataclass, field

from google.protobuf.message import Message

from fieldsim.world import MAX_ROBOT_ID, Team, World
from sslnet.ratelog import RateLimitedLog
from sslnet.streams import MISSING_FIELD, parse_message
from sslpb import grsim_packet_pb2 as grsim_pb
from sslpb import grsim_robot_status_pb2 as grsim_status_pb
from sslpb import ssl_gc_common_pb2 as common_pb
from sslpb import ssl_simulation_control_pb2 as control_pb
from sslpb import ssl_simulation_error_pb2 as error_pb
from sslpb import ssl_simulation_robot_control_pb2 as rc_pb
from sslpb import ssl_simulation_robot_feedback_pb2 as fb_pb

log = logging.getLogger(__name__)

CHANNEL_BLUE = "blue"
CHANNEL_YELLOW = "yellow"
CHANNEL_CONTROL = "control"
CHANNEL_GRSIM = "grsim"

ERR_MALFORMED = "MALFORMED_MESSAGE"
ERR_UNKNOWN_ROBOT = "UNKNOWN_ROBOT"
ERR_INVALID_VALUE = "INVALID_VALUE"
ERR_UNSUPPORTED = "UNSUPPORTED_MOVE_COMMAND"
ERR_UNSUPPORTED_FIELD = "UNSUPPORTED_FIELD"


@dataclass
class ProtocolStats:
    """Counters per channel ("blue", "yellow", "control", "grsim")."""

    datagrams: Counter[str] = field(default_factory=Counter)
    malformed: Counter[str] = field(default_factory=Counter)
    errors: Counter[str] = field(default_factory=Counter)  # answered errors, by code


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


def _team_of(value: int) -> Team | None:
    if value == common_pb.YELLOW:
        return Team.YELLOW
    if value == common_pb.BLUE:
        return Team.BLUE
    return None


class CommandHandler:
    """Applies command datagrams to a World; keeps counters."""

    def __init__(self, world: World, ratelog: RateLimitedLog | None = None) -> None:
        self.world = world
        #: grSim status: per team the last Robots_Status sent, per robot the kicks reported
        self._status_sent: dict[Team, bytes] = {}
        self._kicks_seen: dict[tuple[Team, int], int] = {}
        self.stats = ProtocolStats()
        self._log = ratelog if ratelog is not None else RateLimitedLog(log)

    def _parse(self, msg: Message, data: bytes, channel: str) -> str | None:
        """Parses ``data`` into ``msg``: None, or why not (the datagram counted as malformed
        on ``channel`` and logged)."""
        why = parse_message(msg, data)
        if why is None:
            return None
        reason = (f"missing required fields: {why[1]}" if why[0] == MISSING_FIELD
                  else f"cannot decode: {why[1]}")
        self.stats.malformed[channel] += 1
        self._log.warning(f"malformed-{channel}", "malformed %s datagram: %s", channel, reason)
        return reason

    def _refusal(self, response: fb_pb.RobotControlResponse | control_pb.SimulatorResponse,
                 errors: list[error_pb.SimulatorError], what: str, reason: str) -> bytes:
        """The answer to a malformed datagram: its errors and MALFORMED with the reason."""
        self._error(errors, ERR_MALFORMED, f"{what}: {reason}")
        response.errors.extend(errors)
        return response.SerializeToString()

    def _error(
        self,
        errors: list[error_pb.SimulatorError],
        code: str,
        message: str,
        capability: int | None = None,
    ) -> None:
        err = error_pb.SimulatorError(code=code, message=message)
        if capability is not None:
            err.unsupported_capability = capability  # type: ignore[assignment]
        errors.append(err)
        self.stats.errors[code] += 1

    # -- SSL simulation protocol: RobotControl -> RobotControlResponse -------------------------

    def robot_control(self, team: Team, data: bytes) -> bytes:
        channel = CHANNEL_BLUE if team is Team.BLUE else CHANNEL_YELLOW
        self.stats.datagrams[channel] += 1
        response = fb_pb.RobotControlResponse()
        errors: list[error_pb.SimulatorError] = []
        msg = rc_pb.RobotControl()
        why = self._parse(msg, data, channel)
        if why is not None:
            return self._refusal(response, errors, "RobotControl", why)
        for cmd in msg.robot_commands:
            self._robot_command(team, cmd, errors)
        response.errors.extend(errors)
        # like grSim / ER-Force: one RobotFeedback per robot commanded (and on the field),
        # ball contact while the ball touches its kicker face (World: kicker zone)
        for rid in sorted({cmd.id for cmd in msg.robot_commands}):
            robot = self.world.robot(team, rid)
            if robot is not None:
                response.feedback.add(id=robot.id, dribbler_ball_contact=robot.ball_contact)
        return response.SerializeToString()

    def _robot_command(
        self, team: Team, cmd: rc_pb.RobotCommand, errors: list[error_pb.SimulatorError]
    ) -> None:
        world = self.world
        robot = world.robot(team, cmd.id)
        if robot is None:
            self._error(errors, ERR_UNKNOWN_ROBOT, f"no {team.label} robot {cmd.id} on the field")
            return
        forward = left = angular = 0.0
        if cmd.HasField("move_command"):
            which = cmd.move_command.WhichOneof("command")
            if which == "local_velocity":
                lv = cmd.move_command.local_velocity
                forward, left, angular = lv.forward, lv.left, lv.angular
            elif which == "global_velocity":
                gv = cmd.move_command.global_velocity
                c, s = math.cos(robot.theta), math.sin(robot.theta)
                forward = c * gv.vel_x + s * gv.vel_y
                left = -s * gv.vel_x + c * gv.vel_y
                angular = gv.vel_angular
            elif which == "wheel_velocity":
                world.stop_robot(team, cmd.id)
                self._error(
                    errors,
                    ERR_UNSUPPORTED,
                    "wheel velocity is not supported, use local or global velocity",
                    error_pb.SIMULATOR_CAPABILITY_MOVE_WHEEL_VELOCITY,
                )
                return
        kick_angle = math.radians(cmd.kick_angle) if cmd.HasField("kick_angle") else 0.0
        try:
            world.set_command(
                team,
                cmd.id,
                forward,
                left,
                angular,
                cmd.kick_speed,
                kick_angle,
                cmd.dribbler_speed,
            )
        except ValueError as exc:
            self._error(errors, ERR_INVALID_VALUE, f"robot {cmd.id}: {exc}; robot stopped")

    # -- SSL simulation protocol: SimulatorCommand -> SimulatorResponse ------------------------

    def simulator_command(self, data: bytes) -> bytes:
        self.stats.datagrams[CHANNEL_CONTROL] += 1
        response = control_pb.SimulatorResponse()
        errors: list[error_pb.SimulatorError] = []
        msg = control_pb.SimulatorCommand()
        why = self._parse(msg, data, CHANNEL_CONTROL)
        if why is not None:
            return self._refusal(response, errors, "SimulatorCommand", why)
        if msg.HasField("control"):
            ctl = msg.control
            if ctl.HasField("teleport_ball"):
                self._teleport_ball(ctl.teleport_ball, errors)
            for tr in ctl.teleport_robot:
                self._teleport_robot(tr, errors)
            if ctl.HasField("simulation_speed") and ctl.simulation_speed != 1.0:
                self._error(errors, ERR_UNSUPPORTED_FIELD, "simulation_speed is not supported")
        if msg.HasField("config"):
            self._error(errors, ERR_UNSUPPORTED_FIELD, "SimulatorConfig is not supported")
        response.errors.extend(errors)
        return response.SerializeToString()

    def _teleport_ball(
        self, tb: control_pb.TeleportBall, errors: list[error_pb.SimulatorError]
    ) -> None:
        ball = self.world.ball
        x = tb.x if tb.HasField("x") else ball.x
        y = tb.y if tb.HasField("y") else ball.y
        z = tb.z if tb.HasField("z") else 0.0
        try:
            self.world.teleport_ball(x, y, tb.vx, tb.vy, z, tb.vz)
        except ValueError as exc:
            self._error(errors, ERR_INVALID_VALUE, f"teleport ball: {exc}")

    def _teleport_robot(
        self, tr: control_pb.TeleportRobot, errors: list[error_pb.SimulatorError]
    ) -> None:
        team = _team_of(tr.id.team)
        rid = tr.id.id
        if team is None or not tr.id.HasField("id") or not 0 <= rid <= MAX_ROBOT_ID:
            self._error(errors, ERR_UNKNOWN_ROBOT, f"teleport robot: bad id {tr.id}")
            return
        if tr.HasField("present") and not tr.present:
            self.world.remove_robot(team, rid)
            return
        try:
            ok = self.world.teleport_robot(
                team,
                rid,
                tr.x if tr.HasField("x") else None,
                tr.y if tr.HasField("y") else None,
                tr.orientation if tr.HasField("orientation") else None,
                tr.v_x,
                tr.v_y,
                tr.v_angular,
                add=tr.HasField("present") and tr.present,
            )
        except ValueError as exc:
            self._error(errors, ERR_INVALID_VALUE, f"teleport robot {rid}: {exc}")
            return
        if not ok:
            self._error(
                errors, ERR_UNKNOWN_ROBOT, f"no {team.label} robot {rid}; set present=true to add"
            )

    # -- legacy grSim_Packet (no response) -----------------------------------------------------

    def grsim_status(self, team: Team) -> bytes | None:
        """grSim's Robots_Status of ``team`` (every robot on the field: infrared = ball
        contact, flat / chip kick since the last status), or None when nothing changed since
        the last one returned (grSim sends only on a change)."""
        msg = grsim_status_pb.Robots_Status()
        for robot in sorted(self.world.robots.values(), key=lambda r: r.id):
            if robot.team is not team:
                continue
            key = (team, robot.id)
            kicked = robot.kicks != self._kicks_seen.get(key, robot.kicks)
            self._kicks_seen[key] = robot.kicks
            msg.robots_status.add(robot_id=robot.id, infrared=robot.ball_contact,
                                  flat_kick=kicked and not robot.last_kick_chip,
                                  chip_kick=kicked and robot.last_kick_chip)
        data = msg.SerializeToString()
        if data == self._status_sent.get(team):
            return None
        self._status_sent[team] = data
        return data

    def grsim_packet(self, data: bytes) -> Team | None:
        """Applies a grSim_Packet; the team it commands (None: no commands)."""
        self.stats.datagrams[CHANNEL_GRSIM] += 1
        msg = grsim_pb.grSim_Packet()
        if self._parse(msg, data, CHANNEL_GRSIM) is not None:
            return None
        errors: list[error_pb.SimulatorError] = []
        commanded: Team | None = None
        if msg.HasField("commands"):
            team = Team.YELLOW if msg.commands.isteamyellow else Team.BLUE
            commanded = team
            for rc in msg.commands.robot_commands:
                self._grsim_robot(team, rc, errors)
        if msg.HasField("replacement"):
            rep = msg.replacement
            if rep.HasField("ball"):
                b = rep.ball
                x = b.x if b.HasField("x") else self.world.ball.x
                y = b.y if b.HasField("y") else self.world.ball.y
                try:
                    self.world.teleport_ball(x, y, b.vx, b.vy)
                except ValueError as exc:
                    self._error(errors, ERR_INVALID_VALUE, f"ball replacement: {exc}")
            for rr in rep.robots:
                team = Team.YELLOW if rr.yellowteam else Team.BLUE
                if not 0 <= rr.id <= MAX_ROBOT_ID:
                    self._error(errors, ERR_UNKNOWN_ROBOT, f"robot id {rr.id}")
                    continue
                if rr.HasField("turnon") and not rr.turnon:
                    self.world.remove_robot(team, rr.id)
                    continue
                try:
                    self.world.teleport_robot(
                        team, rr.id, rr.x, rr.y, math.radians(rr.dir), add=True
                    )
                except ValueError as exc:
                    self._error(errors, ERR_INVALID_VALUE, f"robot replacement: {exc}")
        for err in errors:
            self._log.warning(f"grsim-{err.code}", "grSim packet: %s", err.message)
        return commanded

    def _grsim_robot(
        self, team: Team, rc: grsim_pb.grSim_Robot_Command, errors: list[error_pb.SimulatorError]
    ) -> None:
        if self.world.robot(team, rc.id) is None:
            self._error(errors, ERR_UNKNOWN_ROBOT, f"no {team.label} robot {rc.id}")
            return
        if rc.wheelsspeed:
            self.world.stop_robot(team, rc.id)
            self._error(errors, ERR_UNSUPPORTED, "grSim wheel speeds are not supported")
            return
        kx, kz = rc.kickspeedx, rc.kickspeedz
        kick = math.hypot(kx, kz) if _finite(kx, kz) else math.nan
        angle = math.atan2(kz, kx) if kick > 0.0 else 0.0
        try:
            self.world.set_command(
                team,
                rc.id,
                rc.veltangent,
                rc.velnormal,
                rc.velangular,
                kick,
                angle,
                1000.0 if rc.spinner else 0.0,
            )
        except ValueError as exc:
            self._error(errors, ERR_INVALID_VALUE, f"robot {rc.id}: {exc}; robot stopped")
