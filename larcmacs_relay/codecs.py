"""Pure codecs of the relay: validation, command conversion and output encodings.

No sockets, no event loop, no clock (times are arguments), so all of it is testable directly.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from typing import NamedTuple

from google.protobuf import empty_pb2
from google.protobuf.message import Message

from sslnet import streams
from sslpb import (
    grsim_packet_pb2,
    grsim_robot_status_pb2,
    ssl_gc_common_pb2,
    ssl_gc_referee_message_pb2,
    ssl_simulation_control_pb2,
    ssl_simulation_robot_control_pb2,
    ssl_simulation_robot_feedback_pb2,
    touchline_pb2,
)
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket

TEAM_YELLOW = touchline_pb2.TEAM_YELLOW
TEAM_BLUE = touchline_pb2.TEAM_BLUE
TEAMS = (TEAM_BLUE, TEAM_YELLOW)
MAX_ROBOT_ID = 15

# Seed power scale (DESIGN.md s.3): linear power * 0.05 m/s, angular power / 5 rad/s.
MPS_PER_POWER = 0.05
POWER_PER_RADPS = 5.0
MAX_POWER = 100.0

ROBOT_BOX_OPCODE = 1
ROBOT_BOX_SIZE = 13


def team_name(team: int) -> str:
    return "blue" if team == TEAM_BLUE else "yellow" if team == TEAM_YELLOW else "unknown"


# --------------------------------------------------------------------------- input validation


def _parse(msg: Message, data: bytes) -> str | None:
    """The reason ``data`` is refused as ``msg`` (read back by ``classify``), or None."""
    why = streams.parse_message(msg, data)
    if why is None:
        return None
    if why[0] == streams.MISSING_FIELD:
        return f"{msg.DESCRIPTOR.name} misses required fields: {why[1]}"
    return f"does not parse as {msg.DESCRIPTOR.name}: {why[1]}"


def classify(reason: str, data: bytes) -> str:
    """The reason kind (sslnet.streams) of a validation failure of ``data``."""
    if reason.startswith("does not parse as"):
        return streams.wire_problem(data)
    if "misses required fields" in reason:
        return streams.MISSING_FIELD
    if reason.startswith("empty "):
        return streams.NO_CONTENT
    return streams.OTHER


def check_forwarded(data: bytes) -> str | None:
    """Vision and referee datagrams are forwarded unchanged and decoded once, by the backend
    (which counts what does not parse, by reason): here only an empty datagram is refused."""
    return None if data else "empty datagram"


def parse_referee(data: bytes) -> tuple[ssl_gc_referee_message_pb2.Referee | None, str | None]:
    """The Referee in ``data`` (for the compat output, which re-encodes it), or the reason."""
    ref = ssl_gc_referee_message_pb2.Referee()
    reason = _parse(ref, data)
    return (ref, None) if reason is None else (None, reason)


def validate_tracker(data: bytes) -> str | None:
    """Tracker packets: Touchline has no TrackerWrapperPacket schema, so only the protobuf wire
    format is checked (parsed as a message with only unknown fields), and empty is rejected."""
    if not data:
        return "empty tracker datagram"
    return _parse(empty_pb2.Empty(), data)


def parse_tracked_out(data: bytes) -> tuple[TrackerWrapperPacket | None, str | None]:
    """The station's tracked vision ("tracker-out"), checked before it goes on the network:
    it must parse as a TrackerWrapperPacket with every required field, a non-empty uuid (the
    game controller tells trackers apart by it) and a tracked frame. Returns the packet or
    the reason (``classify`` gives its kind)."""
    if not data:
        return None, "empty tracked vision"
    pkt = TrackerWrapperPacket()
    reason = _parse(pkt, data)
    if reason is not None:
        return None, reason
    if not pkt.uuid:
        return None, "TrackerWrapperPacket misses required fields: uuid is empty"
    if not pkt.HasField("tracked_frame"):
        return None, "empty TrackerWrapperPacket: no tracked_frame"
    return pkt, None


# --------------------------------------------------------------------------- command model


@dataclass(frozen=True)
class BoxExtras:
    """Seed robot-box fields carried unchanged from a compat (32x13 matrix) command."""

    kick_up: int = 0
    kick_forward: int = 0
    auto_kick: int = 0
    kicker_voltage: int = 0
    dribbler_enable: int = 0
    dribbler_speed: int = 0
    kicker_charge_enable: int = 0
    beep: int = 0


class Command(NamedTuple):
    """One robot's command in SI units, robot-local frame (team uses touchline.Team numbers).

    A NamedTuple, not a frozen dataclass: one is made for every new command of a command set
    (several hundred a second at full scale), and a frozen dataclass's ``__init__`` sets each
    of its nine fields through ``object.__setattr__`` (1.1 us against 0.3 us)."""

    team: int
    id: int
    forward_mps: float = 0.0
    left_mps: float = 0.0
    angular_radps: float = 0.0
    kick_speed_mps: float = 0.0
    chip: bool = False
    dribbler_rpm: float = 0.0
    box: BoxExtras | None = None

    def zero(self) -> Command:
        """The stop command for the same robot: no motion, no kick, no dribbler."""
        return _new_command(Command, (self[0], self[1], 0.0, 0.0, 0.0, 0.0, False, 0.0, None))

    @property
    def is_zero(self) -> bool:
        return self == self.zero()


#: a Command from all its fields at once (NamedTuple's ``__new__`` is a Python function)
_new_command = tuple.__new__


class CommandError(ValueError):
    """A command the relay refuses (bad id, team, or non-finite value)."""


def command_from_proto(cmd: touchline_pb2.RobotCommand) -> Command:
    """Validate a native RobotCommand; raise CommandError with the reason if it is unusable."""
    team, rid = cmd.team, cmd.id
    if team != TEAM_BLUE and team != TEAM_YELLOW:
        raise CommandError(f"robot command with team {team} (must be blue or yellow)")
    if rid > MAX_ROBOT_ID:
        raise CommandError(f"robot command for id {rid} (must be 0..{MAX_ROBOT_ID})")
    # each field read once (a protobuf attribute read is not free: 600 sets x 11 robots a
    # second at 8 cameras x 75 Hz)
    fwd, left, ang = cmd.forward_mps, cmd.left_mps, cmd.angular_radps
    kick, drib = cmd.kick_speed_mps, cmd.dribbler_rpm
    # finite: v - v is 0.0 for every finite v and NaN for an infinity or a NaN (no calls)
    if (fwd - fwd) + (left - left) + (ang - ang) + (kick - kick) + (drib - drib) != 0.0:
        raise CommandError(f"robot command {team_name(team)} {rid} has a non-finite value")
    if kick < 0:
        raise CommandError(f"robot command {team_name(team)} {rid} has a negative kick")
    return _new_command(Command, (team, rid, fwd, left, ang, kick, cmd.chip, drib, None))


# --------------------------------------------------------------------------- power scale


def clamp(value: float, low: float, high: float) -> float:
    return low if value < low else high if value > high else value


def power_to_si(speed_x: float, speed_y: float, speed_r: float) -> tuple[float, float, float]:
    """Seed +-100 power -> (forward m/s, left m/s, angular rad/s).

    SpeedX is forward and SpeedY is left (the seed's column order SpeedX, SpeedY). The linear
    vector's norm is clipped to 100 before * 0.05 m/s; the angular power is clamped to +-100,
    then / 5 rad/s (same sign: positive = counter-clockwise).
    """
    norm = math.hypot(speed_x, speed_y)
    if norm > MAX_POWER:
        speed_x, speed_y = speed_x * MAX_POWER / norm, speed_y * MAX_POWER / norm
    angular = clamp(speed_r, -MAX_POWER, MAX_POWER) / POWER_PER_RADPS
    return speed_x * MPS_PER_POWER, speed_y * MPS_PER_POWER, angular


def si_to_power(forward: float, left: float, angular: float) -> tuple[int, int, int]:
    """(forward m/s, left m/s, angular rad/s) -> seed power (speedX, speedY, speedR) as ints.

    Inverse of power_to_si: linear power = m/s / 0.05 with the vector norm clipped to 100,
    angular power = rad/s * 5 clamped to +-100; rounded to the nearest integer.
    """
    px, py = forward / MPS_PER_POWER, left / MPS_PER_POWER
    norm = math.hypot(px, py)
    if norm > MAX_POWER:
        px, py = px * MAX_POWER / norm, py * MAX_POWER / norm
    pr = clamp(angular * POWER_PER_RADPS, -MAX_POWER, MAX_POWER)
    return round(px), round(py), round(pr)


# --------------------------------------------------------------------------- sim protocol


def kick_components(speed: float, chip: bool, chip_angle_deg: float) -> tuple[float, float]:
    """Kick speed (m/s, 3D) -> (horizontal, vertical) m/s; straight kicks are all horizontal."""
    if not chip or speed == 0.0:
        return speed, 0.0
    rad = math.radians(chip_angle_deg)
    return speed * math.cos(rad), speed * math.sin(rad)


def encode_sim_robot_control(commands: list[Command], chip_angle_deg: float) -> bytes:
    """SSL simulation protocol RobotControl with one local_velocity RobotCommand per robot."""
    msg = ssl_simulation_robot_control_pb2.RobotControl()
    for c in commands:
        rc = msg.robot_commands.add()
        rc.id = c.id
        lv = rc.move_command.local_velocity
        lv.forward = c.forward_mps
        lv.left = c.left_mps
        lv.angular = c.angular_radps
        rc.kick_speed = c.kick_speed_mps
        rc.kick_angle = chip_angle_deg if (c.chip and c.kick_speed_mps > 0) else 0.0
        rc.dribbler_speed = c.dribbler_rpm
    return msg.SerializeToString()


#: one robot's part of RobotControl as protobuf writes it (every field set, proto2: present
#: even when 0): robot_commands (1, 36 bytes) { id (1, varint < 128), move_command (2, 17) {
#: local_velocity (2, 15) { forward (1), left (2), angular (3) } }, kick_speed (3),
#: kick_angle (4), dribbler_speed (5) }, the floats as 32-bit little-endian
_SIM_PART = struct.Struct("<9BfBfBfBfBfBf")


def encode_sim_robot_command(command: Command, chip_angle_deg: float) -> bytes:
    """One robot's part of ``encode_sim_robot_control``: RobotControl has the one repeated
    field, so the parts of several robots, joined, are the message of all of them (byte for
    byte). The relay keeps each robot's part while its command stays the same. Written by
    struct (a tenth of the time of a message built and serialized; the same bytes, tested);
    a value beyond float32 or an id beyond one varint byte goes through protobuf."""
    _, rid, fwd, left, ang, kick, chip, drib, _ = command  # one unpack, not 7 attribute reads
    if 0 <= rid < 128:
        angle = chip_angle_deg if (chip and kick > 0) else 0.0
        try:
            return _SIM_PART.pack(0x0A, 36, 0x08, rid, 0x12, 17, 0x12, 15, 0x0D, fwd,
                                  0x15, left, 0x1D, ang, 0x1D, kick, 0x25, angle, 0x2D, drib)
        except OverflowError:  # float32 has no such value: protobuf makes it infinite
            pass
    return encode_sim_robot_control([command], chip_angle_deg)


def count_response_errors(data: bytes) -> tuple[int, str]:
    """Errors in a RobotControlResponse / SimulatorResponse (both carry errors as field 1).

    Returns (count, description); an unparsable reply counts as one error.
    """
    msg = ssl_simulation_robot_feedback_pb2.RobotControlResponse()
    err = _parse(msg, data)
    if err is not None:
        return 1, err
    if not msg.errors:
        return 0, ""
    first = msg.errors[0]
    return len(msg.errors), f"simulator error {first.code}: {first.message}"


def check_robot_control_response(data: bytes) -> tuple[int, str, str | None]:
    """A simulator's answer on a robot port: (errors it reports, the first one, why it is
    refused: None when it is a valid RobotControlResponse, else the reason kind of
    sslnet.streams). An empty datagram is a valid (empty) response."""
    msg = ssl_simulation_robot_feedback_pb2.RobotControlResponse()
    err = _parse(msg, data)
    if err is not None:
        return 0, err, classify(err, data)
    if not msg.errors:
        return 0, "", None
    first = msg.errors[0]
    return len(msg.errors), f"simulator error {first.code}: {first.message}", None


def check_grsim_status(data: bytes) -> str | None:
    """Why ``data`` is not a grSim Robots_Status (forwarded unchanged when it is), or None."""
    return _parse(grsim_robot_status_pb2.Robots_Status(), data)


# --------------------------------------------------------------------------- grSim legacy


def encode_grsim_commands(
    commands: list[Command], yellow: bool, timestamp_s: float, chip_angle_deg: float
) -> bytes:
    """grSim_Packet with grSim_Commands for one team (veltangent = forward, velnormal = left)."""
    pkt = grsim_packet_pb2.grSim_Packet()
    gc = pkt.commands
    gc.timestamp = timestamp_s
    gc.isteamyellow = yellow
    for c in commands:
        rc = gc.robot_commands.add()
        rc.id = c.id
        kx, kz = kick_components(c.kick_speed_mps, c.chip, chip_angle_deg)
        rc.kickspeedx = kx
        rc.kickspeedz = kz
        rc.veltangent = c.forward_mps
        rc.velnormal = c.left_mps
        rc.velangular = c.angular_radps
        rc.spinner = c.dribbler_rpm > 0
        rc.wheelsspeed = False
    return pkt.SerializeToString()


def sim_command_to_grsim(cmd: ssl_simulation_control_pb2.SimulatorCommand) -> bytes | None:
    """Translate teleport_ball / teleport_robot to a grSim_Replacement packet (None if nothing).

    Metres stay metres; orientation rad -> dir degrees; ``present`` -> ``turnon``. Fields grSim
    cannot express (z, vz, config, simulation speed) are dropped.
    """
    if not cmd.HasField("control"):
        return None
    ctl = cmd.control
    pkt = grsim_packet_pb2.grSim_Packet()
    rep = pkt.replacement
    used = False
    if ctl.HasField("teleport_ball"):
        tb = ctl.teleport_ball
        ball = rep.ball
        ball.SetInParent()
        if tb.HasField("x"):
            ball.x = tb.x
        if tb.HasField("y"):
            ball.y = tb.y
        if tb.HasField("vx"):
            ball.vx = tb.vx
        if tb.HasField("vy"):
            ball.vy = tb.vy
        used = True
    for tr in ctl.teleport_robot:
        r = rep.robots.add()
        r.x = tr.x
        r.y = tr.y
        r.dir = math.degrees(tr.orientation)
        r.id = tr.id.id
        r.yellowteam = tr.id.team == ssl_gc_common_pb2.YELLOW
        if tr.HasField("present"):
            r.turnon = tr.present
        used = True
    return pkt.SerializeToString() if used else None


# --------------------------------------------------------------------------- robot box


def _u8(value: float) -> int:
    return int(clamp(round(value), 0, 255))


def _i8(value: int) -> int:
    return int(clamp(value, -100, 100)) & 0xFF


def encode_robot_box(
    c: Command,
    *,
    kick_mps_per_volt: float = 0.5,
    dribbler_rpm_per_unit: float = 1000.0,
    charge: bool = True,
) -> bytes:
    """The seed's 13-byte robot-box datagram for one robot.

    Byte order: opcode 1, robot number, speedY int8, speedX int8, speedR int8 (sign inverted),
    dribbler speed, kicker voltage, kickUp, kickForward, beep, dribbler enable,
    kicker-charge enable, autoKick. Speeds use the seed's +-100 power scale with SpeedX =
    forward and SpeedY = left (si_to_power). For commands that came through the compat matrix,
    the seed's own kick/dribbler/beep bytes are passed through; for native commands they are
    derived: voltage = kick m/s / kick_mps_per_volt, kickUp = chip, kickForward = straight,
    dribbler speed = rpm / dribbler_rpm_per_unit, dribbler enable = rpm > 0, charge as given.
    A zero (stop) command sends zeros in every byte after the robot number.
    """
    px, py, pr = si_to_power(c.forward_mps, c.left_mps, c.angular_radps)
    if c.box is not None:
        b = c.box
        tail = (
            b.dribbler_speed,
            b.kicker_voltage,
            b.kick_up,
            b.kick_forward,
            b.beep,
            b.dribbler_enable,
            b.kicker_charge_enable,
            b.auto_kick,
        )
    elif c.is_zero:
        tail = (0, 0, 0, 0, 0, 0, 0, 0)
    else:
        kicking = c.kick_speed_mps > 0
        tail = (
            _u8(c.dribbler_rpm / dribbler_rpm_per_unit),
            _u8(c.kick_speed_mps / kick_mps_per_volt) if kicking else 0,
            1 if kicking and c.chip else 0,
            1 if kicking and not c.chip else 0,
            0,
            1 if c.dribbler_rpm > 0 else 0,
            1 if charge else 0,
            0,
        )
    head = (ROBOT_BOX_OPCODE, c.id, _i8(py), _i8(px), _i8(-pr))
    return struct.pack("13B", *head, *(_u8(v) for v in tail))
