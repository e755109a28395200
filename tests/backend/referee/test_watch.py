import logging

import pytest

from backend.referee.watch import REFEREE_SILENT_S, RefereeWatch
from backend.world.referee import RefereeState


class Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def _ref(command: str = "STOP", source: str = "gc-1") -> RefereeState:
    return RefereeState(command=command, stage="NORMAL_FIRST_HALF", command_counter=1,
                        stage_time_left_s=None, blue={}, yellow={}, designated_position=None,
                        blue_team_on_positive_half=None, packet_timestamp_us=0,
                        source_identifier=source)


def test_nothing_to_report_before_a_referee_was_heard() -> None:
    w = RefereeWatch(clock=Clock())
    assert w.status() is None and w.check() is None
    assert RefereeWatch.warning(None) is None


def test_silent_only_after_the_threshold() -> None:
    clock = Clock()
    w = RefereeWatch(clock=clock)
    w.heard(_ref("STOP", "gc-1"))
    clock.t += REFEREE_SILENT_S
    st = w.status()
    assert st is not None
    assert st == {"last_heard_s": REFEREE_SILENT_S, "source_identifier": "gc-1",
                  "command": "STOP", "obeyed": True, "silent": False,
                  "silent_after_s": REFEREE_SILENT_S}
    clock.t += 0.01
    st = w.status()
    assert st is not None and st["silent"] is True
    assert RefereeWatch.warning(st) == "referee silent 3 s: still obeying STOP from gc-1"
    # heard again: no longer silent, the age counts from the new message
    w.heard(_ref("FORCE_START", "gc-1"))
    clock.t += 0.1
    st = w.status()
    assert st is not None and st["silent"] is False and st["command"] == "FORCE_START"
    assert st["last_heard_s"] == pytest.approx(0.1)
    assert RefereeWatch.warning(st) is None


def test_a_referee_the_station_ignores_is_not_silent() -> None:
    # the internal referee, switched off by the operator: its silence is expected
    clock = Clock()
    w = RefereeWatch(clock=clock)
    w.obeyed = lambda: False
    w.heard(_ref())
    clock.t += 60.0
    st = w.status()
    assert st is not None and st["silent"] is False and st["obeyed"] is False


def test_each_transition_is_logged_once(caplog: pytest.LogCaptureFixture) -> None:
    clock = Clock()
    w = RefereeWatch(clock=clock)
    w.heard(_ref("STOP", "gc-1"))
    with caplog.at_level(logging.INFO, logger="touchline.referee"):
        w.check()
        assert caplog.records == []
        clock.t += 3.5
        for _ in range(5):  # the ingest checks twice a second
            w.check()
            clock.t += 0.5
        silent = [r for r in caplog.records if "silent" in r.getMessage()]
        assert len(silent) == 1 and silent[0].levelno == logging.WARNING
        assert "gc-1" in silent[0].getMessage() and "STOP" in silent[0].getMessage()
        w.heard(_ref("STOP", "gc-1"))
        w.check()
        w.check()
        back = [r for r in caplog.records if "heard again" in r.getMessage()]
        assert len(back) == 1 and back[0].levelno == logging.INFO
        assert len(caplog.records) == 2


def test_a_new_game_controller_is_not_the_silent_one_back(
        caplog: pytest.LogCaptureFixture) -> None:
    """A GC restarted has a new source identifier: the log says which fell silent and which
    is heard now (found by hand: it said the new one was "heard again")."""
    clock = Clock()
    w = RefereeWatch(clock=clock)
    w.heard(_ref("STOP", "gc-1"))
    w.check()
    clock.t += 3.5
    with caplog.at_level(logging.INFO, logger="touchline.referee"):
        w.check()
        w.heard(_ref("HALT", "gc-2"))
        w.check()
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 2, lines
    assert lines[1] == "referee gc-2 heard (gc-1 fell silent before)"
