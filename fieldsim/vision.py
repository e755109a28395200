"""Pure vision core: true world state -> per-camera SSL detection frames, with faults.

Each camera sees a rectangle of the field (a quadrant for 4 cameras, a half for 2) extended by
``camera_overlap_mm`` past the centre lines, so objects near the centre are reported by several
cameras, each with its own noise, like SSL-Vision. Faults: Gaussian noise on position and
orientation, missed detections (per object and camera), false balls (on a robot or anywhere in
view). Every camera has its own random stream and frame counter, so output is deterministic for
a seed and a sequence of calls. A ball in the air is reported where the camera's ray through it
meets the ground (``cameras.Camera.ground_point``), with no height, as SSL-Vision does; the
other balls left on the field (``World.other_balls``) are detected like the ball.
"""

from __future__ import annotations

import random
from collections.abc import Iterator

from fieldsim.cameras import Camera, camera_calibration, make_cameras
from fieldsim.config import SimConfig
from fieldsim.geometry import FieldGeometry, field_size_message
from fieldsim.world import ROBOT_HEIGHT_M, Team, World, wrap_angle
from sslpb import ssl_vision_detection_pb2 as det_pb
from sslpb import ssl_vision_wrapper_pb2 as wrapper_pb

__all__ = ["Camera", "Vision", "WorldClockFrames", "camera_calibration", "make_cameras"]


class Vision:
    """Turns the world into detection frames; one random stream and counter per camera."""

    def __init__(self, config: SimConfig, geometry: FieldGeometry) -> None:
        self.config = config
        self.geometry = geometry
        self.cameras = make_cameras(config, geometry)
        self._rng = [
            random.Random(f"fieldsim-cam-{config.seed}-{c.camera_id}") for c in self.cameras
        ]
        self.frame_numbers = [rng.randrange(0, 100_000) for rng in self._rng]
        # each camera's own clock (t_capture_camera) is offset from Unix time
        self.clock_offsets = [rng.uniform(-1000.0, 1000.0) for rng in self._rng]
        self.phases = [rng.uniform(0.0, 1.0 / config.camera_hz) for rng in self._rng]
        if config.camera_phases == "together":  # (drawn all the same: the noise stays)
            self.phases = [0.0] * len(self.phases)
        self.false_detections = 0
        self.missed_detections = 0

    def detect(
        self,
        camera_id: int,
        world: World,
        t_capture: float,
        t_sent: float | None = None,
        extrapolate_s: float = 0.0,
    ) -> wrapper_pb.SSL_WrapperPacket:
        """A wrapper with the detection frame camera ``camera_id`` captures of ``world`` now.

        ``t_capture`` is Unix seconds of the capture; ``extrapolate_s`` moves objects along their
        velocity to the capture instant when it lies between physics steps.
        """
        cfg = self.config
        cam = self.cameras[camera_id]
        rng = self._rng[camera_id]
        packet = wrapper_pb.SSL_WrapperPacket()
        packet.source = wrapper_pb.SSL_SOURCE_OTHER
        frame = packet.detection
        frame.frame_number = self.frame_numbers[camera_id]
        self.frame_numbers[camera_id] += 1
        frame.t_capture = t_capture
        frame.t_sent = t_capture if t_sent is None else t_sent
        frame.t_capture_camera = t_capture + self.clock_offsets[camera_id]
        frame.camera_id = camera_id
        noise, noise_rad, miss = cfg.noise_mm, cfg.noise_rad, cfg.miss_prob

        for ball in (world.ball, *world.other_balls):
            # at the capture instant: along the velocity, and up or down the parabola in flight
            bz = ball.z + ball.vz * extrapolate_s
            if ball.z > 0.0:
                bz -= world.config.gravity * extrapolate_s * extrapolate_s / 2.0
            bx, by = cam.ground_point((ball.x + ball.vx * extrapolate_s) * 1000.0,
                                      (ball.y + ball.vy * extrapolate_s) * 1000.0,
                                      max(0.0, bz) * 1000.0)
            if not cam.sees(bx, by):
                continue
            if miss > 0.0 and rng.random() < miss:
                self.missed_detections += 1
            else:
                self._add_ball(frame, cam, rng, bx + rng.gauss(0.0, noise),
                               by + rng.gauss(0.0, noise), 0.0, self._confidence(rng))

        visible: list[tuple[float, float]] = []
        for robot in world.robots.values():
            rx = (robot.x + robot.vx * extrapolate_s) * 1000.0
            ry = (robot.y + robot.vy * extrapolate_s) * 1000.0
            if not cam.sees(rx, ry):
                continue
            visible.append((rx, ry))
            if miss > 0.0 and rng.random() < miss:
                self.missed_detections += 1
                continue
            det = (frame.robots_blue if robot.team is Team.BLUE else frame.robots_yellow).add()
            det.confidence = self._confidence(rng)
            det.robot_id = robot.id
            det.x = rx + rng.gauss(0.0, noise)
            det.y = ry + rng.gauss(0.0, noise)
            det.orientation = wrap_angle(robot.theta + robot.omega * extrapolate_s
                                         + rng.gauss(0.0, noise_rad))
            det.pixel_x, det.pixel_y = cam.pixel(det.x, det.y, ROBOT_HEIGHT_M * 1000.0)
            det.height = ROBOT_HEIGHT_M * 1000.0

        if cfg.false_prob > 0.0 and rng.random() < cfg.false_prob:
            self.false_detections += 1
            if visible and rng.random() < 0.5:
                fx, fy = visible[rng.randrange(len(visible))]
                fx += rng.gauss(0.0, 10.0)
                fy += rng.gauss(0.0, 10.0)
            else:
                fx, fy = rng.uniform(cam.x0, cam.x1), rng.uniform(cam.y0, cam.y1)
            self._add_ball(frame, cam, rng, fx, fy, 0.0, rng.uniform(0.3, cfg.confidence))
        return packet

    def _confidence(self, rng: random.Random) -> float:
        return min(1.0, max(0.0, rng.gauss(self.config.confidence, 0.02)))

    @staticmethod
    def _add_ball(
        frame: det_pb.SSL_DetectionFrame,
        cam: Camera,
        rng: random.Random,
        x: float,
        y: float,
        z: float,
        confidence: float,
    ) -> None:
        det = frame.balls.add()
        det.confidence = confidence
        det.area = 70 + rng.randrange(0, 20)
        det.x, det.y = x, y
        if z > 0.0:
            det.z = z
        det.pixel_x, det.pixel_y = cam.pixel(x, y, z)

    def geometry_packet(self) -> wrapper_pb.SSL_WrapperPacket:
        """A wrapper with geometry only: field size, lines, arcs and one calibration per camera."""
        packet = wrapper_pb.SSL_WrapperPacket()
        packet.source = wrapper_pb.SSL_SOURCE_OTHER
        packet.geometry.field.CopyFrom(field_size_message(self.geometry))
        for cam in self.cameras:
            packet.geometry.calib.append(camera_calibration(cam))
        return packet


class WorldClockFrames:
    """Every camera's frames on the world's own clock, with no socket and no wall clock (the
    loops of tests, benchmarks and digests; the server schedules its own): camera k captures
    at its phase, then once a period; the capture stamped ``t0_unix + tc``, sent 1 ms later."""

    def __init__(self, vision: Vision, world: World, t0_unix: float) -> None:
        self.vision, self.world, self.t0_unix = vision, world, t0_unix
        self.period = 1.0 / vision.config.camera_hz
        self.next_capture = [world.t + ph for ph in vision.phases]

    def due(self) -> Iterator[tuple[int, float, wrapper_pb.SSL_WrapperPacket]]:
        """(camera, capture time ``tc`` on the world's clock, the packet) of each frame due by
        the world's time, camera by camera; each made when the caller takes it."""
        w, v, t0, nxt, period = self.world, self.vision, self.t0_unix, self.next_capture, \
            self.period
        for k in range(len(nxt)):
            while nxt[k] <= w.t:
                tc = nxt[k]
                nxt[k] += period
                yield k, tc, v.detect(k, w, t0 + tc, t0 + tc + 0.001, tc - w.t)
