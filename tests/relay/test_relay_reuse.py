"""The relay's reuse of parsed commands and encoded output: what it sends is always what it
would send with nothing reused (no sockets: a Relay not running, its output recorded)."""

from __future__ import annotations

import math
import random

import pytest

from larcmacs_relay import Relay, RelayConfig, codecs
from larcmacs_relay import command_input as relay
from larcmacs_relay.codecs import Command
from larcmacs_relay.commands import CommandTable
from sslpb import touchline_pb2

BLUE, YELLOW = touchline_pb2.TEAM_BLUE, touchline_pb2.TEAM_YELLOW


class Recorder:
    """Stands in for the relay's UDP output socket."""

    def __init__(self) -> None:
        self.sent: list[tuple[bytes, tuple[str, int]]] = []

    def sendto(self, data: bytes, addr: tuple[str, int]) -> int:
        self.sent.append((data, addr))
        return len(data)


def robot(team: int, rid: int, k: int) -> Command:
    """Robot ``rid``'s command number ``k`` of a small pool (so that commands come back)."""
    return Command(team, rid, forward_mps=0.25 * (k % 3), left_mps=-0.5 if k % 2 else 0.0,
                   angular_radps=0.125 * k, kick_speed_mps=2.0 if k == 3 else 0.0,
                   chip=k == 3, dribbler_rpm=100.0 * (k % 2))


def command_set(cmds: list[Command], nan_for: int | None = None) -> bytes:
    cset = touchline_pb2.RobotCommandSet(source_receive_time_ns=1)
    for c in cmds:
        cset.commands.add(team=c.team, id=c.id, forward_mps=c.forward_mps,  # type: ignore[arg-type]
                          left_mps=c.left_mps, angular_radps=c.angular_radps,
                          kick_speed_mps=c.kick_speed_mps, chip=c.chip,
                          dribbler_rpm=c.dribbler_rpm)
    if nan_for is not None:
        cset.commands.add(team=BLUE, id=nan_for, forward_mps=math.nan)  # type: ignore[arg-type]
    return cset.SerializeToString()


@pytest.mark.parametrize("max_parsed", [2, 512])
def test_every_datagram_is_the_fresh_encoding_of_the_commands_due(
        monkeypatch: pytest.MonkeyPatch, max_parsed: int) -> None:
    monkeypatch.setattr(relay, "MAX_PARSED", max_parsed)  # 2: started afresh all the time
    cfg = RelayConfig()
    r = Relay(cfg)
    out = Recorder()
    r._udp_out = out  # type: ignore[assignment]
    rng = random.Random(11)
    robots = [(BLUE, i) for i in range(6)] + [(YELLOW, i) for i in range(3)]
    choice = {key: 0 for key in robots}
    now = 100.0
    for n in range(300):
        for key in rng.sample(robots, rng.randint(0, 3)):  # a few robots change per set
            choice[key] = rng.randint(0, 4)
        expected = [robot(team, rid, choice[(team, rid)]) for team, rid in robots]
        bad = rng.choice([None, None, None, 7])
        errors = r.streams["commands"].errors
        r._handle_native([b"commands", command_set(expected, bad)])
        assert r.streams["commands"].errors == errors + (bad is not None)  # counted each time
        out.sent.clear()
        for repeat in range(1 + n % 2):  # and a repeat cycle of the same commands
            assert r.output_cycle(now + 0.001 * repeat)
        now += 0.005
        assert len(out.sent) == 2 * (1 + n % 2)
        for data, addr in out.sent:
            team = BLUE if addr[1] == cfg.sim_blue_port else YELLOW
            fresh = codecs.encode_sim_robot_control([c for c in expected if c.team == team],
                                                    cfg.chip_angle_deg)
            assert data == fresh, f"set {n}"


def test_update_all_is_update_in_order() -> None:
    a, b = CommandTable(), CommandTable()
    first = [Command(BLUE, 1, 0.5), Command(YELLOW, 2, 0.1)]
    for c in first:
        a.update(c, 1.0)
    b.update_all(first, 1.0)
    a.stop_all(1.05)
    b.stop_all(1.05)
    second = [Command(BLUE, 1, 0.7), Command(BLUE, 4, 0.2), Command(BLUE, 1, 0.9)]
    for c in second:
        a.update(c, 1.1)
    b.update_all(second, 1.1)
    assert sorted(a.due(1.15), key=lambda c: c.id) == [
        Command(BLUE, 1, 0.9), Command(YELLOW, 2), Command(BLUE, 4, 0.2)]
    assert a.due(1.16) == b.due(1.16)
    assert a.due(1.3) == b.due(1.3) and a.stale_stops == b.stale_stops == 2
