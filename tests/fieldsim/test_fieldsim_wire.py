"""Wire compatibility from field numbers (not from our own generated code), and the CLI."""

from __future__ import annotations

import os
import random
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fieldsim.config import SimConfig
from fieldsim.protocol import CommandHandler
from fieldsim.vision import Vision
from fieldsim.world import Team, World
from sslnet.multicast import loopback_multicast_ok, open_multicast_receiver
from sslpb import ssl_simulation_robot_feedback_pb2 as fb_pb
from tests.wire import f32, key, ld, read_fields, varint

REPO = Path(__file__).resolve().parents[2]


def test_hand_built_robot_control_is_accepted() -> None:
    local = f32(1, 1.0) + f32(2, 0.0) + f32(3, 0.0)  # MoveLocalVelocity forward/left/angular
    move = ld(2, local)  # RobotMoveCommand.local_velocity = 2
    command = key(1, 0) + varint(3) + ld(2, move)  # RobotCommand id=3, move=2
    data = ld(1, command)  # RobotControl.robot_commands = 1
    world = World(SimConfig())
    handler = CommandHandler(world)
    reply = fb_pb.RobotControlResponse()
    reply.ParseFromString(handler.robot_control(Team.BLUE, data))
    assert not reply.errors
    robot = world.robot(Team.BLUE, 3)
    assert robot is not None and robot.command is not None
    assert (robot.command.forward, robot.command.left, robot.command.angular) == (1.0, 0.0, 0.0)
    # the reply, read by hand: feedback = field 2, RobotFeedback.id = field 1 varint
    fields = read_fields(handler.robot_control(Team.BLUE, data))
    ids = [read_fields(v)[0][2] for f, w, v in fields if f == 2 and isinstance(v, bytes)]
    assert ids == [3]  # one RobotFeedback per robot commanded
    # missing required id: rejected
    bad = ld(1, ld(2, move))
    reply.ParseFromString(handler.robot_control(Team.BLUE, bad))
    assert reply.errors and handler.stats.malformed["blue"] == 1


def test_detection_packet_decodes_by_field_number() -> None:
    cfg = SimConfig(miss_prob=0.0)
    world = World(cfg)
    vision = Vision(cfg, world.geometry)
    data = vision.detect(2, world, 1700000000.25, 1700000000.26).SerializeToString()
    wrapper = read_fields(data)
    (detection,) = [v for f, w, v in wrapper if f == 1 and w == 2]
    assert isinstance(detection, bytes)
    fields = {f: (w, v) for f, w, v in read_fields(detection)}
    assert fields[4] == (0, 2)  # camera_id, varint
    w, raw = fields[2]  # t_capture, fixed64 double
    assert w == 1 and isinstance(raw, bytes)
    assert struct.unpack("<d", raw)[0] == 1700000000.25
    w, raw = fields[3]  # t_sent
    assert w == 1 and isinstance(raw, bytes)
    assert struct.unpack("<d", raw)[0] == 1700000000.26
    assert fields[1][0] == 0  # frame_number, varint
    # source = field 3 of the wrapper, SSL_SOURCE_OTHER = 1
    assert (3, 0, 1) in wrapper
    # a blue robot (field 7): x = field 3 fixed32 float in mm
    blue = [v for f, w, v in read_fields(detection) if f == 7]
    assert blue
    robot_fields = {f: v for f, w, v in read_fields(blue[0])}  # type: ignore[arg-type]
    x = struct.unpack("<f", robot_fields[3])[0]  # type: ignore[arg-type]
    assert -4600 < x < 0


@pytest.mark.skipif(not loopback_multicast_ok(), reason="no multicast on loopback")
def test_cli_runs_and_stops_cleanly_on_sigterm() -> None:
    port = random.SystemRandom().randint(20000, 40000)
    rx = open_multicast_receiver("224.5.23.2", port, "127.0.0.1")
    rx.setblocking(True)
    rx.settimeout(0.5)
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldsim", "--vision-port", str(port), "--control-port", "0",
         "--blue-port", "0", "--yellow-port", "0", "--grsim-port", "0", "--seed", "3"],
        cwd=REPO, env=env, stderr=subprocess.PIPE, text=True,
    )
    try:
        got = False
        deadline = time.monotonic() + 10.0
        while not got and time.monotonic() < deadline:
            try:
                got = len(rx.recv(65536)) > 0
            except TimeoutError:
                assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
        assert got, "no vision packet from the CLI"
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=5.0)
        assert proc.returncode == 0, err
        assert f"vision -> 224.5.23.2:{port}" in err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        rx.close()


def test_cli_rejects_bad_flags() -> None:
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.run(
        [sys.executable, "-m", "fieldsim", "--blue", "12"],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=10,
    )
    assert proc.returncode == 2
    assert "blue must be in 0..11" in proc.stderr
