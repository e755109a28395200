"""Pure codecs of the seed LARCmaCS contract (DESIGN.md s.3): referee JSON and the 32x13 matrix."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

from larcmacs_relay.codecs import (
    TEAM_BLUE,
    TEAM_YELLOW,
    BoxExtras,
    Command,
    clamp,
    power_to_si,
)
from sslpb import ssl_gc_referee_message_pb2

Ref = ssl_gc_referee_message_pb2.Referee

# Seed referee states and teams.
HALT, STOP, RUNNING, TIMEOUT, POST_GAME = 0, 1, 2, 3, 4
PREPARE_KICKOFF, KICKOFF, PREPARE_PENALTY, PENALTY = 5, 6, 7, 8
DIRECT_FREE, INDIRECT_FREE, BALL_PLACEMENT = 9, 10, 11
NEUTRAL, BLUE, YELLOW = 0, 1, 2

# Referee command -> (seed state, seed team).
_COMMAND_MAP: dict[int, tuple[int, int]] = {
    Ref.HALT: (HALT, NEUTRAL),
    Ref.STOP: (STOP, NEUTRAL),
    Ref.NORMAL_START: (RUNNING, NEUTRAL),  # refined by the previous command below
    Ref.FORCE_START: (RUNNING, NEUTRAL),
    Ref.PREPARE_KICKOFF_YELLOW: (PREPARE_KICKOFF, YELLOW),
    Ref.PREPARE_KICKOFF_BLUE: (PREPARE_KICKOFF, BLUE),
    Ref.PREPARE_PENALTY_YELLOW: (PREPARE_PENALTY, YELLOW),
    Ref.PREPARE_PENALTY_BLUE: (PREPARE_PENALTY, BLUE),
    Ref.DIRECT_FREE_YELLOW: (DIRECT_FREE, YELLOW),
    Ref.DIRECT_FREE_BLUE: (DIRECT_FREE, BLUE),
    Ref.INDIRECT_FREE_YELLOW: (INDIRECT_FREE, YELLOW),
    Ref.INDIRECT_FREE_BLUE: (INDIRECT_FREE, BLUE),
    Ref.TIMEOUT_YELLOW: (TIMEOUT, YELLOW),
    Ref.TIMEOUT_BLUE: (TIMEOUT, BLUE),
    Ref.GOAL_YELLOW: (STOP, NEUTRAL),
    Ref.GOAL_BLUE: (STOP, NEUTRAL),
    Ref.BALL_PLACEMENT_YELLOW: (BALL_PLACEMENT, YELLOW),
    Ref.BALL_PLACEMENT_BLUE: (BALL_PLACEMENT, BLUE),
}


class RefereeMapper:
    """Maps Referee messages to the seed's {"state", "team", "is_left"}.

    It remembers the command before the current one (by ``command_counter``), so that
    NORMAL_START after PREPARE_KICKOFF_X is KICKOFF for X and after PREPARE_PENALTY_X is
    PENALTY for X; any other NORMAL_START and FORCE_START are RUNNING. Stage POST_GAME wins
    over the command. ``is_left`` is 1 when our team defends the negative-x (left) half:
    blue defends the positive half iff ``blue_team_on_positive_half`` (unset = false, the
    proto2 default, so blue is left).
    """

    def __init__(self, our_team: str = "blue") -> None:
        self.our_blue = our_team == "blue"
        self._counter: int | None = None
        self._command: int | None = None
        self._previous: int | None = None

    def state(self, ref: ssl_gc_referee_message_pb2.Referee) -> dict[str, int]:
        if ref.command_counter != self._counter:
            self._previous = self._command
            self._command = ref.command
            self._counter = ref.command_counter
        state, team = _COMMAND_MAP.get(ref.command, (HALT, NEUTRAL))
        if ref.command == Ref.NORMAL_START and self._previous is not None:
            prev_state, prev_team = _COMMAND_MAP.get(self._previous, (HALT, NEUTRAL))
            if prev_state == PREPARE_KICKOFF:
                state, team = KICKOFF, prev_team
            elif prev_state == PREPARE_PENALTY:
                state, team = PENALTY, prev_team
        if ref.stage == Ref.POST_GAME:
            state, team = POST_GAME, NEUTRAL
        blue_positive = ref.blue_team_on_positive_half
        our_positive = blue_positive if self.our_blue else not blue_positive
        return {"state": state, "team": team, "is_left": 0 if our_positive else 1}

    def encode(self, ref: ssl_gc_referee_message_pb2.Referee) -> bytes:
        return json.dumps(self.state(ref)).encode()


# --------------------------------------------------------------------------- command matrix

MATRIX_ROWS = 32
MATRIX_COLS = 13
MATRIX_BYTES = MATRIX_ROWS * MATRIX_COLS * 8  # 3328

COL_VALID, COL_SPEED_X, COL_SPEED_Y, COL_SPEED_R = 0, 1, 2, 3
COL_KICK_UP, COL_KICK_FORWARD, COL_AUTO_KICK, COL_KICKER_VOLTAGE = 4, 5, 6, 7
COL_DRIBBLER_ENABLE, COL_DRIBBLER_SPEED, COL_CHARGE_ENABLE, COL_BEEP = 8, 9, 10, 11


@dataclass(frozen=True)
class MatrixResult:
    commands: list[Command]
    errors: list[str]


def _byte(value: float) -> int:
    return int(clamp(round(value), 0, 255))


def decode_command_matrix(
    data: bytes,
    *,
    kick_mps_per_volt: float = 0.5,
    max_kick_mps: float = 6.5,
    dribbler_rpm_per_unit: float = 1000.0,
) -> MatrixResult:
    """The seed strategy-bridge's 32x13 float64 (C order) matrix -> commands for valid rows.

    Row r: blue id r for r < 16, yellow id r-16 otherwise; column 0 == 1 marks a valid row.
    Speeds go through power_to_si. A kick (KickForward, or KickUp = chip) has speed
    KickerVoltage * kick_mps_per_volt capped at max_kick_mps; dribbler rpm = DribblerSpeed *
    dribbler_rpm_per_unit when DribblerEnable. The seed bytes are kept for the robot box.
    Raises ValueError if the size is wrong; rows with non-finite values are reported in errors.
    """
    # numpy here, not at import: it is only for --compat, and importing it took most of a
    # (re)started relay's time to come up (bench/restart_bench.py)
    import numpy as np

    if len(data) != MATRIX_BYTES:
        raise ValueError(f"command matrix has {len(data)} bytes, expected {MATRIX_BYTES}")
    m = np.frombuffer(data, dtype="<f8").reshape(MATRIX_ROWS, MATRIX_COLS)
    commands: list[Command] = []
    errors: list[str] = []
    for row in range(MATRIX_ROWS):
        r = m[row]
        if not math.isfinite(float(r[COL_VALID])) or round(float(r[COL_VALID])) != 1:
            continue
        values = [float(v) for v in r[:12]]
        team = TEAM_BLUE if row < 16 else TEAM_YELLOW
        rid = row % 16
        if not all(math.isfinite(v) for v in values):
            errors.append(f"matrix row {row} has a non-finite value")
            continue
        fwd, left, ang = power_to_si(values[COL_SPEED_X], values[COL_SPEED_Y], values[COL_SPEED_R])
        box = BoxExtras(
            kick_up=_byte(values[COL_KICK_UP]),
            kick_forward=_byte(values[COL_KICK_FORWARD]),
            auto_kick=_byte(values[COL_AUTO_KICK]),
            kicker_voltage=_byte(values[COL_KICKER_VOLTAGE]),
            dribbler_enable=_byte(values[COL_DRIBBLER_ENABLE]),
            dribbler_speed=_byte(values[COL_DRIBBLER_SPEED]),
            kicker_charge_enable=_byte(values[COL_CHARGE_ENABLE]),
            beep=_byte(values[COL_BEEP]),
        )
        kicking = box.kick_up > 0 or box.kick_forward > 0
        kick = min(box.kicker_voltage * kick_mps_per_volt, max_kick_mps) if kicking else 0.0
        rpm = box.dribbler_speed * dribbler_rpm_per_unit if box.dribbler_enable else 0.0
        commands.append(
            Command(
                team=team,
                id=rid,
                forward_mps=fwd,
                left_mps=left,
                angular_radps=ang,
                kick_speed_mps=kick,
                chip=box.kick_up > 0,
                dribbler_rpm=rpm,
                box=box,
            )
        )
    return MatrixResult(commands, errors)
