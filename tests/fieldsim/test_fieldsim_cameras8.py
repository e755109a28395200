"""fieldsim's eight cameras (division A) through its real UDP output on loopback.

The simulator runs as ``python -m fieldsim --cameras 8`` (the command line the launcher and
the benches use) and is driven only through its wire: the ball is placed with SimulatorCommand
teleports on the control port, and what the cameras saw is read from the vision multicast.
Nothing here imports fieldsim's internals, so the test holds however fieldsim is split up.
"""

from __future__ import annotations

import itertools
import random
import socket
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from sslnet.multicast import loopback_multicast_ok, open_multicast_receiver
from sslpb import ssl_simulation_control_pb2 as control_pb
from sslpb import ssl_vision_wrapper_pb2 as wrapper_pb

pytestmark = pytest.mark.skipif(not loopback_multicast_ok(), reason="no multicast on loopback")

ROOT = Path(__file__).resolve().parents[2]
GROUP = "224.5.23.2"
CAMERAS = 8
HZ = 75.0
Packet = wrapper_pb.SSL_WrapperPacket


def _free_udp_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port: int = s.getsockname()[1]
    s.close()
    return port


@dataclass
class Sim:
    """A running ``python -m fieldsim`` and the test's two sockets on its wire."""

    proc: subprocess.Popen[bytes]
    rx: socket.socket  # vision multicast
    ctl: socket.socket  # connected to the control port
    half_x_mm: float = 0.0  # field of play plus boundary, from the geometry packet
    half_y_mm: float = 0.0
    centres: dict[int, tuple[float, float]] | None = None  # camera id -> (x, y) mm

    def packets(self, timeout: float = 5.0) -> Iterator[Packet]:
        """Vision packets as they arrive; fails if none comes for ``timeout`` seconds."""
        while True:
            self.rx.settimeout(timeout)
            try:
                data = self.rx.recv(65536)
            except TimeoutError:
                raise AssertionError(f"no vision datagram for {timeout} s") from None
            p = Packet.FromString(data)
            assert p.IsInitialized()
            yield p

    def drain(self) -> None:
        self.rx.setblocking(False)
        try:
            while True:
                self.rx.recv(65536)
        except BlockingIOError:
            pass
        finally:
            self.rx.setblocking(True)

    def teleport_ball(self, x_mm: float, y_mm: float) -> None:
        cmd = control_pb.SimulatorCommand()
        tb = cmd.control.teleport_ball
        tb.x, tb.y, tb.z, tb.vx, tb.vy = x_mm / 1000.0, y_mm / 1000.0, 0.0, 0.0, 0.0
        self.ctl.send(cmd.SerializeToString())
        self.ctl.settimeout(5.0)
        reply = control_pb.SimulatorResponse.FromString(self.ctl.recv(65536))
        assert not reply.errors, reply.errors

    def ball_seen_by(self, x_mm: float, y_mm: float) -> dict[int, tuple[float, float]]:
        """Teleport the ball to (x, y), then one detection frame from every camera (all
        captured after the teleport): camera id -> the ball it reports (none: not in it)."""
        self.teleport_ball(x_mm, y_mm)
        # the reply left after the teleport and before any later capture, and loopback
        # delivers at sendto: whatever is queued now was captured before it
        self.drain()
        seen: dict[int, tuple[float, float]] = {}
        heard: set[int] = set()
        for p in self.packets():
            if not p.HasField("detection"):
                continue
            d = p.detection
            heard.add(d.camera_id)
            balls = [(b.x, b.y) for b in d.balls]
            assert len(balls) <= 1, balls  # no false balls configured
            if balls:
                seen[d.camera_id] = balls[0]
            if len(heard) == CAMERAS:
                return seen
        raise AssertionError("unreachable")


def _start(*args: str) -> Sim:
    vport, cport = random.SystemRandom().randint(20000, 40000), _free_udp_port()
    rx = open_multicast_receiver(GROUP, vport, "127.0.0.1")
    rx.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)  # 8 x 75 Hz: no overflow
    proc = subprocess.Popen(
        [sys.executable, "-m", "fieldsim", "--division", "A", "--cameras", str(CAMERAS),
         "--camera-hz", str(HZ), "--vision-group", GROUP, "--vision-port", str(vport),
         "--interface", "127.0.0.1", "--control-port", str(cport), "--blue-port", "0",
         "--yellow-port", "0", "--grsim-port", "0", "--grsim-status-blue-port", "0",
         "--grsim-status-yellow-port", "0", "--log-level", "WARNING", *args],
        cwd=ROOT)
    ctl = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ctl.connect(("127.0.0.1", cport))
    sim = Sim(proc, rx, ctl)
    try:
        for p in sim.packets(timeout=20.0):  # the first geometry packet: field and cameras
            if p.HasField("geometry"):
                f = p.geometry.field
                sim.half_x_mm = f.field_length / 2 + f.boundary_width
                sim.half_y_mm = f.field_width / 2 + f.boundary_width
                sim.centres = {c.camera_id: (c.derived_camera_world_tx,
                                             c.derived_camera_world_ty) for c in p.geometry.calib}
                break
    except BaseException:
        _stop(sim)
        raise
    return sim


def _stop(sim: Sim) -> None:
    sim.proc.terminate()
    try:
        sim.proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        sim.proc.kill()
        sim.proc.wait()
    sim.rx.close()
    sim.ctl.close()


@pytest.fixture(scope="module")
def ball_only() -> Iterator[Sim]:
    """No robots, no noise, no misses, no false balls: only the cameras' layout decides."""
    sim = _start("--blue", "0", "--yellow", "0", "--noise-mm", "0", "--noise-rad", "0",
                 "--miss-prob", "0", "--false-prob", "0", "--seed", "3")
    try:
        yield sim
    finally:
        _stop(sim)


def test_eight_camera_ids_and_calibrations(ball_only: Sim) -> None:
    assert ball_only.centres is not None and sorted(ball_only.centres) == list(range(CAMERAS))
    # two rows of four along the field: four distinct columns, two rows
    xs = sorted({round(c[0]) for c in ball_only.centres.values()})
    ys = sorted({round(c[1]) for c in ball_only.centres.values()})
    assert len(xs) == 4 and len(ys) == 2 and ys[0] < 0 < ys[1]


def test_every_point_of_the_field_is_seen(ball_only: Sim) -> None:
    """A grid over the field of play and its boundary (edges included, a ball radius in):
    at every point at least one camera reports the ball, where it is."""
    margin = 30.0
    nx, ny = 13, 9
    xs = [-ball_only.half_x_mm + margin + i * (2 * (ball_only.half_x_mm - margin)) / (nx - 1)
          for i in range(nx)]
    ys = [-ball_only.half_y_mm + margin + j * (2 * (ball_only.half_y_mm - margin)) / (ny - 1)
          for j in range(ny)]
    unseen = []
    for x, y in itertools.product(xs, ys):
        seen = ball_only.ball_seen_by(x, y)
        if not seen:
            unseen.append((x, y))
        for bx, by in seen.values():
            assert abs(bx - x) < 1.0 and abs(by - y) < 1.0, (x, y, seen)
    assert not unseen, f"points no camera sees: {unseen}"


def test_neighbouring_cameras_overlap_on_the_same_ball(ball_only: Sim) -> None:
    """Midway between two neighbouring cameras (a row's neighbours, and the camera across the
    field's long axis) both report the ball, at the same place (no noise configured)."""
    centres = ball_only.centres
    assert centres is not None
    by_pos = sorted(centres, key=lambda k: (-centres[k][1], centres[k][0]))
    rows = [by_pos[:4], by_pos[4:]]
    pairs = [(r[i], r[i + 1]) for r in rows for i in range(3)]
    pairs += [(rows[0][i], rows[1][i]) for i in range(4)]
    for (a, b), step in itertools.product(pairs, (-150.0, 150.0)):
        # 150 mm to either side of the border: inside both views, not on the one line
        # where two touching (not overlapping) views would both claim the ball
        ax, ay = centres[a]
        bx, by = centres[b]
        dist = ((bx - ax) ** 2 + (by - ay) ** 2) ** 0.5
        x = (ax + bx) / 2 + step * (bx - ax) / dist
        y = (ay + by) / 2 + step * (by - ay) / dist
        seen = ball_only.ball_seen_by(x, y)
        assert a in seen and b in seen, (a, b, step, sorted(seen))
        assert seen[a] == pytest.approx(seen[b], abs=1e-3), (a, b, seen)
    # the centre spot: both rows' two middle cameras
    assert len(ball_only.ball_seen_by(0.0, 0.0)) >= 4


def test_frame_numbers_and_rate_per_camera_at_11v11() -> None:
    """Division A, 11 v 11, 8 cameras at 75 Hz: per camera the frame numbers go up by one
    and the capture times are 1/75 s apart (counted over frames, not measured with a clock)."""
    sim = _start("--blue", "11", "--yellow", "11")
    try:
        frames: dict[int, list[tuple[int, float]]] = {k: [] for k in range(CAMERAS)}
        want = 150  # 2 s of frames per camera
        deadline = time.monotonic() + 60.0  # bounds a stuck simulator, not a speed check
        for p in sim.packets():
            assert time.monotonic() < deadline, {k: len(v) for k, v in frames.items()}
            if not p.HasField("detection"):
                continue
            d = p.detection
            assert 0 <= d.camera_id < CAMERAS
            frames[d.camera_id].append((d.frame_number, d.t_capture))
            if all(len(v) >= want for v in frames.values()):
                break
        for k, fs in frames.items():
            nums = [n for n, _ in fs]
            assert all(b == a + 1 for a, b in itertools.pairwise(nums)), (k, nums)
            gaps = [b - a for (_, a), (_, b) in itertools.pairwise(fs)]
            # a frame the simulator was too late for is skipped (a gap of two periods),
            # like a real camera's; the typical gap is the period
            assert statistics.median(gaps) == pytest.approx(1.0 / HZ, rel=1e-3), k
            assert min(gaps) >= 1.0 / HZ * (1 - 1e-3), k
        # the cameras are not in phase (real ones are not synchronised)
        phases = {round((fs[0][1] % (1.0 / HZ)) * 1e4) for fs in frames.values()}
        assert len(phases) > 1
    finally:
        _stop(sim)


def test_cameras_together_capture_at_once_and_arrive_as_one_burst() -> None:
    """``--camera-phases together`` (cameras triggered together, as grSim sends its four in
    one burst per step): every camera's frame of an instant has the same capture time, and
    the frames of an instant arrive one after the other, the eight of them, before any frame
    of the next instant (sent back to back; the timing of the burst is bench/burst_bench.py's,
    not a test's). The default (spread) was checked above: the cameras are not in phase."""
    sim = _start("--blue", "11", "--yellow", "11", "--camera-phases", "together")
    try:
        arrivals: list[tuple[float, int]] = []  # (capture time, camera) in arrival order
        deadline = time.monotonic() + 60.0  # bounds a stuck simulator, not a speed check
        for p in sim.packets():
            assert time.monotonic() < deadline, len(arrivals)
            if p.HasField("detection"):
                arrivals.append((p.detection.t_capture, p.detection.camera_id))
            if len(arrivals) >= 100 * CAMERAS:
                break
        # from the first whole instant on (the first one read may have begun before)
        start = next(i for i, (t, _) in enumerate(arrivals) if i and t != arrivals[i - 1][0])
        bursts = [list(g) for _, g in itertools.groupby(arrivals[start:], key=lambda a: a[0])]
        bursts = bursts[:-1]  # the last one read may be cut short
        assert len(bursts) >= 90
        for b in bursts:  # each instant: its eight cameras in a row, then the next instant
            assert sorted(c for _, c in b) == list(range(CAMERAS)), b
        times = [b[0][0] for b in bursts]
        assert all(t1 > t0 for t0, t1 in itertools.pairwise(times))
    finally:
        _stop(sim)
