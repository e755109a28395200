"""The log player on a real log file (written with LogWriter, opened with LogFile), its clock
driven by hand: what is emitted when, seek with pre-roll, frame steps, jumps, the end."""

from __future__ import annotations

from pathlib import Path

import pytest

from backend.replay.player import PREROLL_S, LogPlayer, PlayerError
from ssllog.format import TYPE_REFEREE_2013, TYPE_TL_COMMANDS, TYPE_TL_HEALTH, TYPE_VISION_2014
from ssllog.logfile import LogFile
from ssllog.reader import Record
from ssllog.writer import LogWriter
from sslpb import ssl_gc_referee_message_pb2, ssl_vision_wrapper_pb2, touchline_pb2

S = 1_000_000_000
T0 = 1_700_000_000 * S
FRAME = S // 60
Referee = ssl_gc_referee_message_pb2.Referee


def _wrapper(frame: int) -> bytes:
    w = ssl_vision_wrapper_pb2.SSL_WrapperPacket()
    d = w.detection
    d.frame_number, d.camera_id = frame, 0
    d.t_capture = d.t_sent = (T0 + frame * FRAME) / S
    return w.SerializeToString()


def _referee(counter: int, command: int) -> bytes:
    r = Referee(packet_timestamp=1, stage=Referee.NORMAL_FIRST_HALF, command=command,
                command_counter=counter, command_timestamp=1)
    for info in (r.yellow, r.blue):
        info.name, info.score, info.red_cards, info.yellow_cards = "x", 0, 0, 0
        info.timeouts, info.timeout_time, info.goalkeeper = 0, 0, 0
    return r.SerializeToString()


@pytest.fixture
def log(tmp_path: Path) -> LogFile:
    """3 s: one camera at 60 Hz, the referee at 10 Hz: HALT, STOP at 1 s, FORCE_START at 2 s."""
    path = tmp_path / "t.log"
    w = LogWriter(str(path))
    for i in range(181):
        t = T0 + i * FRAME
        w.write(t, TYPE_VISION_2014, _wrapper(i))
        if i % 6 == 0:
            cmd, counter = ((Referee.HALT, 1) if i < 60 else
                            (Referee.STOP, 2) if i < 120 else (Referee.FORCE_START, 3))
            w.write(t + 1000, TYPE_REFEREE_2013, _referee(counter, cmd))
    w.finish()
    return LogFile.open(str(path), tmp_path / "cache")


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


class Harness:
    def __init__(self, log: LogFile) -> None:
        self.clock = Clock()
        self.out: list[Record] = []
        self.resets = 0
        self.player = LogPlayer(self.out.append, self._reset, self.clock)
        self.player.attach(log)

    def _reset(self) -> None:
        self.resets += 1

    def drain(self) -> None:
        """Emits what is due until nothing is (as the feed does, a batch a wake-up)."""
        for _ in range(10_000):
            batch = self.player.due()
            if not batch:
                return
            self.player.emit(batch)
        raise AssertionError("the player never ran dry")

    def vision_times(self) -> list[int]:
        return [r.time_ns for r in self.out if r.type == TYPE_VISION_2014]


def test_open_shows_the_first_frame_paused(log: LogFile) -> None:
    h = Harness(log)
    h.drain()
    assert h.vision_times() == [T0]
    assert not h.player.playing and h.player.position_s() == 0.0
    assert h.player.wait_s() is None  # paused: the feed sleeps until woken
    v = h.player.view()
    assert v["source"] == "log" and v["duration_s"] == pytest.approx(3.0, abs=0.01)
    assert [e["label"] for e in v["events"] if e["kind"] == "command"][:3] == [
        "HALT", "STOP", "FORCE_START"]


def test_play_emits_on_the_log_clock_at_any_speed(log: LogFile) -> None:
    h = Harness(log)
    h.drain()
    h.player.play(2.0)
    h.clock.t += 0.25  # 0.5 s of log at 2x
    h.drain()
    assert h.vision_times()[-1] == T0 + 30 * FRAME
    assert h.player.now_ns() == T0 + S // 2
    wait = h.player.wait_s()
    assert wait is not None and 0 < wait <= FRAME / S / 2 + 1e-9


def test_as_fast_as_possible_plays_to_the_end_and_stops(log: LogFile) -> None:
    h = Harness(log)
    h.player.play(0)
    h.drain()
    assert len(h.vision_times()) == 181
    assert not h.player.playing
    assert h.player.position_s() == pytest.approx(h.player.duration_s())
    h.player.play(1.0)  # at the end: plays again from the start
    assert h.player.position_s() == 0.0


def test_seek_resets_and_prerolls_to_the_position(log: LogFile) -> None:
    h = Harness(log)
    h.drain()
    epoch, resets = h.player.epoch, h.resets
    h.out.clear()
    h.player.seek(1.5)
    h.drain()
    times = h.vision_times()
    assert h.player.epoch == epoch + 1 and h.resets == resets + 1
    assert times[0] >= T0 + int((1.5 - PREROLL_S) * S) - FRAME
    assert times[-1] <= T0 + int(1.5 * S) and T0 + int(1.5 * S) - times[-1] < FRAME
    assert h.player.position_s() == pytest.approx(1.5)
    assert not h.player.playing


def test_steps_one_camera_frame_forward_and_back(log: LogFile) -> None:
    h = Harness(log)
    h.player.seek(1.0)
    h.drain()
    here = h.vision_times()[-1]
    h.player.step(1)
    h.drain()
    assert h.vision_times()[-1] == here + FRAME
    assert h.player.now_ns() == here + FRAME
    h.player.step(3)
    h.drain()
    assert h.player.now_ns() == here + 4 * FRAME
    h.player.step(-2)
    h.drain()
    assert h.player.now_ns() == here + 2 * FRAME
    assert h.vision_times()[-1] == here + 2 * FRAME


def test_steps_from_a_pause_go_from_where_the_playhead_stopped(log: LogFile) -> None:
    """The feed may lag the playhead by a few records when playing stops: a step forward goes
    to the first frame after the playhead (never back), a step back to the last one before."""
    h = Harness(log)
    h.player.seek(1.0)
    h.drain()
    h.player.play(1.0)
    h.clock.t += 0.1 + FRAME / S / 2  # the playhead is 6.5 frames on, nothing fed yet
    h.player.pause()
    paused = h.player.now_ns()
    h.player.step(1)
    h.drain()
    assert h.player.now_ns() > paused
    assert h.player.now_ns() - paused <= FRAME
    assert h.vision_times()[-1] == h.player.now_ns()
    h.player.step(-1)
    h.drain()
    assert h.player.now_ns() < paused
    assert paused - h.player.now_ns() <= FRAME
    # paused with the feed behind and stepped back at once: one frame before the playhead
    h.player.play(1.0)
    h.clock.t += 0.1
    h.player.pause()
    paused = h.player.now_ns()
    h.drain()  # the feed catches up (woken by the pause)
    assert h.vision_times()[-1] <= paused
    assert paused - h.vision_times()[-1] < FRAME
    h.player.step(-1)
    h.drain()
    assert 0 < paused - h.player.now_ns() <= FRAME


def test_jumps_to_referee_commands(log: LogFile) -> None:
    h = Harness(log)
    h.drain()
    assert h.player.jump("command", "next") == pytest.approx(1.0, abs=0.02)
    assert h.player.jump("command", "next") == pytest.approx(2.0, abs=0.02)
    with pytest.raises(PlayerError, match="no next command"):
        h.player.jump("command", "next")
    assert h.player.jump("command", "prev") == pytest.approx(1.0, abs=0.02)
    with pytest.raises(PlayerError, match="no next goal"):
        h.player.jump("goal", "next")


@pytest.mark.parametrize("speed", [-1.0, 0.05, 11.0, float("nan"), float("inf")])
def test_bad_speed_refused_with_reason(log: LogFile, speed: float) -> None:
    h = Harness(log)
    with pytest.raises(PlayerError, match="speed must be"):
        h.player.play(speed)
    assert not h.player.playing


def test_seek_outside_the_log_refused(log: LogFile) -> None:
    h = Harness(log)
    with pytest.raises(PlayerError, match="past the end"):
        h.player.seek(10.0)
    with pytest.raises(PlayerError):
        h.player.seek(-1.0)


def test_live_detaches(log: LogFile) -> None:
    h = Harness(log)
    h.player.live()
    assert h.player.source == "live" and h.player.clock() is None
    with pytest.raises(PlayerError, match="no log is open"):
        h.player.play(1.0)


def test_the_delivered_clock_waits_for_the_feed(log: LogFile) -> None:
    """Vision is judged by the log's time up to which the feed emitted every record: while a
    seek's pre-roll comes a batch at a time, or a fast replay's feed lags the playhead, the
    frames not emitted yet are no silence; caught up, it is the playhead."""
    h = Harness(log)
    h.drain()
    h.player.seek(1.5)
    target = T0 + int(1.5 * S)
    assert h.player.position_ns() == target
    first = h.player.delivered_ns()
    # just before the pre-roll's first record: nothing of it emitted yet
    assert first < T0 + int((1.5 - PREROLL_S) * S) + FRAME
    h.drain()
    assert h.player.delivered_ns() == target  # caught up: the playhead (paused)
    h.player.play(10.0)
    h.clock.t += 0.1  # one second of log at 10x, nothing emitted yet
    assert h.player.position_ns() == pytest.approx(target + S, abs=1_000)
    assert h.player.delivered_ns() < target + FRAME
    h.player.emit(h.player.due())  # one batch (70 records are due)
    assert h.out[-1].time_ns <= h.player.delivered_ns() < h.out[-1].time_ns + FRAME
    assert h.player.delivered_ns() < target + S // 2
    h.drain()
    assert h.player.delivered_ns() == h.player.position_ns()


def test_the_commands_the_log_sent_are_played_the_rest_of_its_own_records_skipped(
        tmp_path: Path) -> None:
    """The commands a Touchline log recorded (type 1001) come out of the feed in order with
    the vision, so the station can draw them beside what its strategy commands now (what-if);
    its other records (health, parameters) and unknown types do not."""
    path = tmp_path / "c.log"
    w = LogWriter(str(path))
    sent: list[tuple[int, bytes]] = []
    for i in range(60):
        t = T0 + i * FRAME
        w.write(t, TYPE_VISION_2014, _wrapper(i))
        cs = touchline_pb2.RobotCommandSet(created_time_ns=t + 500, sequence=i + 1)
        cs.commands.add(team=touchline_pb2.TEAM_BLUE, id=3, forward_mps=0.01 * i)
        sent.append((t + 500, cs.SerializeToString()))
        w.write(t + 500, TYPE_TL_COMMANDS, sent[-1][1])
        if i % 10 == 0:
            w.write(t + 700, TYPE_TL_HEALTH, b'{"ok": true}')
            w.write(t + 800, 4242, b"unknown")
    w.finish()
    h = Harness(LogFile.open(str(path), tmp_path / "cache"))
    h.player.play(0)
    h.drain()
    assert {r.type for r in h.out} == {TYPE_VISION_2014, TYPE_TL_COMMANDS}
    assert [(r.time_ns, r.payload) for r in h.out if r.type == TYPE_TL_COMMANDS] == sent
    times = [r.time_ns for r in h.out]
    assert times == sorted(times)
    # after a seek, from the pre-roll on, as the vision is
    h.out.clear()
    h.player.seek(0.5)
    h.drain()
    cmds = [r.time_ns for r in h.out if r.type == TYPE_TL_COMMANDS]
    assert cmds and cmds[0] >= T0 + int((0.5 - PREROLL_S) * S) - FRAME
    assert cmds[-1] <= T0 + S // 2


@pytest.mark.parametrize("speed", [0.0, 1.0])
def test_a_record_stamped_after_the_next_does_not_hold_the_end(tmp_path: Path,
                                                               speed: float) -> None:
    """A command record is stamped when sent, up to a few ms after the vision record written
    next (84 of the fixture's 538 are): the log still plays to its end, every record out."""
    path = tmp_path / "late.log"
    w = LogWriter(str(path))
    for i in range(30):
        t = T0 + i * FRAME
        w.write(t, TYPE_VISION_2014, _wrapper(i))
        if i == 28:  # the last command: 2 ms after the last vision record, written before it
            w.write(T0 + 29 * FRAME + 2_000_000, TYPE_TL_COMMANDS,
                    touchline_pb2.RobotCommandSet(sequence=1).SerializeToString())
    w.finish()
    h = Harness(LogFile.open(str(path), tmp_path / "cache"))
    h.drain()
    h.player.play(speed)
    h.clock.t += 1.0  # past the end at 1x
    h.drain()
    assert len(h.vision_times()) == 30 and sum(r.type == TYPE_TL_COMMANDS for r in h.out) == 1
    assert not h.player.playing
    assert h.player.position_s() == pytest.approx(h.player.duration_s())
