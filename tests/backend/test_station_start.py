"""The station's start in order (backend/startup.py): what the first command needs (ZeroMQ, the
processors, the e-stop and the arming) first; the session recorder's file and the compute
engine only once the first command set went to the relay, or after a bound without one (no
vision). In-process, on real ZeroMQ sockets; the order is read from the station's own
timeline, no durations are asserted."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from backend.config import Settings
from backend.station import Station
from backend.world.state import BallState, RobotState, WorldState
from launcher.supervisor import free_tcp_port
from tests.waiting import wait_until


def _settings(tmp_path: Path, **kw: Any) -> Settings:
    return Settings(relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                    relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                    state_dir=tmp_path / "state", **kw)


def _world() -> WorldState:
    robots = (RobotState("blue", 3, -1000.0, 0.0, 0.0, t_seen=10.0),)
    return WorldState(10.0, time.time_ns(), BallState(1.0, 2.0, t_seen=10.0), robots)


def test_the_recorder_and_the_engine_start_after_the_first_command(tmp_path: Path) -> None:
    st = Station(_settings(tmp_path, late_start_max_s=600.0,
                           set_params=["strategy.engine=numpy"]))
    st.start_thread()
    try:
        steps = st.startup.view()["steps_s"]
        assert isinstance(steps, dict) and "station running" in steps
        # running, and nothing of the rest yet: no vision, so no command
        assert not st.late_started.is_set()
        assert st.recording.recorder is None and st.strategy.engine is None
        assert "recorder open" not in steps and "engine started" not in steps
        # vision (the world a camera frame makes), until the first command set has left
        # for the relay: the strategy's targets, then control's commands
        while not st.late_started.wait(0.01):
            st.call_sync(st.world_topic.write, _world())
            assert time.monotonic() - st.started_mono < 60, "no first command"
        steps = st.startup.view()["steps_s"]
        assert isinstance(steps, dict)
        assert steps["first targets"] <= steps["first command"] <= steps["recorder open"]
        assert st.recording.recorder is not None and st.recording.recorder.status()["enabled"]
        wait_until(lambda: st.strategy.engine is not None, 20.0, 0.01)  # the numpy engine's worker
        steps = st.startup.view()["steps_s"]
        assert isinstance(steps, dict)
        assert steps["first command"] < steps["engine started"]
    finally:
        st.stop_thread()


def test_without_vision_the_rest_starts_after_its_bound(tmp_path: Path) -> None:
    st = Station(_settings(tmp_path, late_start_max_s=0.2))
    st.start_thread()
    try:
        assert st.late_started.wait(20)
        steps = st.startup.view()["steps_s"]
        assert isinstance(steps, dict)
        assert "recorder open" in steps and "first command" not in steps
        assert st.recording.recorder is not None
    finally:
        st.stop_thread()


def test_with_no_bound_everything_starts_at_once(tmp_path: Path) -> None:
    """Tests and tools that build a station in-process (late_start_max_s 0) get it whole."""
    st = Station(_settings(tmp_path))
    st.start_thread()
    try:
        assert st.late_started.is_set() and st.recording.recorder is not None
    finally:
        st.stop_thread()
