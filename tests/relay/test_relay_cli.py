"""The command line: starts, publishes stats, stops cleanly on SIGTERM / SIGINT."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest
import zmq

from larcmacs_relay.__main__ import build_parser, config_from_args
from tests.relay.conftest import free_udp_port, random_multicast_port


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
