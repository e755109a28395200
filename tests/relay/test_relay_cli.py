"""The command line: starts, publishes stats, stops cleanly on SIGTERM / SIGINT."""

from __future__ import annotations

import os
import pstats
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import zmq

from larcmacs_relay.__main__ import build_parser, config_from_args
from tests.ports import free_udp_port, random_multicast_port


def test_flags_build_config() -> None:
    args = build_parser().parse_args(
        ["--vision", "224.5.23.2:10006", "--output", "robot-box", "--robot-box", "10.0.0.5:10001",
         "--tracker", "224.5.23.2:10010", "--rate", "150", "--compat", "--our-team", "yellow"]
    )  # fmt: skip
    cfg = config_from_args(args)
    assert (cfg.vision_group, cfg.vision_port) == ("224.5.23.2", 10006)
    assert (cfg.output, cfg.robot_box_host, cfg.robot_box_port) == ("robot-box", "10.0.0.5", 10001)
    assert cfg.tracker_enabled and cfg.tracker_port == 10010
    assert cfg.output_rate_hz == 150 and cfg.compat and cfg.our_team == "yellow"
    with pytest.raises(ValueError):
        config_from_args(build_parser().parse_args(["--rate", "50"])).validate()


def test_min_gap_flag() -> None:
    sim = config_from_args(build_parser().parse_args(["--rate", "125"]))
    assert sim.output == "sim" and sim.min_gap_s == 0.0  # a simulator: every set at once
    box = config_from_args(build_parser().parse_args(["--rate", "125", "--output",
                                                      "robot-box"]))
    assert box.min_gap_s == pytest.approx(0.004)  # real robots: half a period
    cfg = config_from_args(build_parser().parse_args(["--min-gap", "0"]))
    cfg.validate()
    assert cfg.min_gap_s == 0.0
    for bad in ("-0.001", "0.05"):  # negative, or longer than a period (120 Hz)
        with pytest.raises(ValueError, match="min_output_gap_s"):
            config_from_args(build_parser().parse_args(["--min-gap", bad])).validate()


def test_feedback_interval_flag() -> None:
    assert config_from_args(build_parser().parse_args([])).feedback_interval_s == 0.02
    cfg = config_from_args(build_parser().parse_args(["--feedback-interval", "0"]))
    cfg.validate()
    assert cfg.feedback_interval_s == 0.0  # every answer forwarded
    for bad in ("-0.01", "0.06"):  # held answers must stay well inside the contact's 0.2 s
        with pytest.raises(ValueError, match="feedback_interval_s"):
            config_from_args(build_parser().parse_args(["--feedback-interval", bad])).validate()


def test_profile_written_on_stop(tmp_path: Path) -> None:
    """--profile FILE: the cProfile stats are there after a normal stop (bench/ reads them)."""
    out = tmp_path / "relay.prof"
    pub = f"tcp://127.0.0.1:{free_udp_port()}"
    cmd = [
        sys.executable, "-m", "larcmacs_relay", "--profile", str(out),
        "--vision", f"224.5.23.2:{random_multicast_port()}",
        "--referee", f"224.5.23.1:{random_multicast_port()}",
        "--pub", pub, "--sub", f"tcp://127.0.0.1:{free_udp_port()}",
        "--sim-blue-port", str(free_udp_port()), "--sim-yellow-port", str(free_udp_port()),
        "--sim-control-port", str(free_udp_port()),
    ]  # fmt: skip
    proc = subprocess.Popen(cmd, env=dict(os.environ, PYTHONPATH=os.getcwd()),
                            stderr=subprocess.PIPE, text=True)
    ctx = zmq.Context()
    try:
        sub = ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.SUBSCRIBE, b"stats")
        sub.connect(pub)
        assert sub.poll(10_000), "no stats from the relay process"
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=10)
        assert proc.returncode == 0, err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        ctx.destroy(linger=0)
    stats = pstats.Stats(str(out))
    profiled = stats.stats  # type: ignore[attr-defined]
    assert any(f.endswith("relay.py") and fn == "_stats_loop" for (f, _, fn) in profiled)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_cli_runs_and_stops_cleanly(sig: signal.Signals) -> None:
    pub = f"tcp://127.0.0.1:{free_udp_port()}"
    cmd = [
        sys.executable, "-m", "larcmacs_relay",
        "--vision", f"224.5.23.2:{random_multicast_port()}",
        "--referee", f"224.5.23.1:{random_multicast_port()}",
        "--pub", pub, "--sub", f"tcp://127.0.0.1:{free_udp_port()}",
        "--sim-blue-port", str(free_udp_port()), "--sim-yellow-port", str(free_udp_port()),
        "--sim-control-port", str(free_udp_port()),
    ]  # fmt: skip
    env = dict(os.environ, PYTHONPATH=os.getcwd())
    proc = subprocess.Popen(cmd, env=env, stderr=subprocess.PIPE, text=True)
    ctx = zmq.Context()
    try:
        sub = ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.LINGER, 0)
        sub.setsockopt(zmq.SUBSCRIBE, b"stats")
        sub.connect(pub)
        assert sub.poll(10_000), "no stats from the relay process"
        assert sub.recv_multipart()[0] == b"stats"
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=10)
        assert proc.returncode == 0, err
        assert "relay stopped" in err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        ctx.destroy(linger=0)
