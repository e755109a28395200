"""Pure vision core: true world state -> per-camera SSL detection frames, with faults.

Each camera sees a rectangle of the field (a quadrant for 4 cameras, a half for 2) extended by
``camera_overlap_mm`` past the centre lines, so objects near the centre are reported by several
cameras, each with its own noise, like SSL-Vision. Faults: Gaussian noise on position and
orientation, missed detections (per object and camera), false balls (on a robot or anywhere in
view). Every camera has its own random stream and frame counter, so output is deterministic for
a seed and a sequence of calls.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

from fieldsim.config import SimConfig
from fieldsim.geometry import FieldGeometry, field_size_message
from fieldsim.world import ROBOT_HEIGHT_M, Team, World, wrap_angle
from sslpb import ssl_vision_detection_pb2 as det_pb
from sslpb import ssl_vision_geometry_pb2 as geom_pb
from sslpb import ssl_vision_wrapper_pb2 as wrapper_pb

IMAGE_WIDTH = 1280
IMAGE_HEIGHT = 1024


@dataclass(frozen=True)
class Camera:
    """A camera looking straight down at (cx, cy) from height h; it sees [x0,x1] x [y0,y1]."""

    camera_id: int
    cx: float  # mm
    cy: float
    height: float
    x0: float
    x1: float
    y0: float
    y1: float
    focal: float  # px

    def sees(self, x: float, y: float) -> bool:
        return self.x0 <= x <= self.x1 and self.y0 <= y <= self.y1

    def pixel(self, x: float, y: float, z: float = 0.0) -> tuple[float, float]:
        """Pinhole projection of a field point (mm) to pixels."""
        depth = max(1.0, self.height - z)
        px = IMAGE_WIDTH / 2.0 + self.focal * (x - self.cx) / depth
        py = IMAGE_HEIGHT / 2.0 - self.focal * (y - self.cy) / depth
        return px, py


def make_cameras(config: SimConfig, geometry: FieldGeometry) -> list[Camera]:
    """Camera ids 0..n-1. Four cameras: 0 (-x,+y), 1 (+x,+y), 2 (-x,-y), 3 (+x,-y). Eight
    cameras (the division A layout of the last world cups): two rows of four along the field,
    ids 0..3 on +y from -x to +x, 4..7 on -y, each overlapping its neighbours by
    ``camera_overlap_mm``."""
    wx, wy, ov, h = geometry.wall_x, geometry.wall_y, config.camera_overlap_mm, (
        config.camera_height_mm
    )
    rects: list[tuple[float, float, float, float]]
    if config.cameras == 1:
        rects = [(-wx, wx, -wy, wy)]
    elif config.cameras == 2:
        rects = [(-wx, ov, -wy, wy), (-ov, wx, -wy, wy)]
    elif config.cameras == 8:
        xs = [-wx + i * wx / 2.0 for i in range(5)]  # four columns
        rects = [(max(-wx, xs[i] - ov), min(wx, xs[i + 1] + ov), y0, y1)
                 for y0, y1 in ((-ov, wy), (-wy, ov)) for i in range(4)]
    else:
        rects = [
            (-wx, ov, -ov, wy),
            (-ov, wx, -ov, wy),
            (-wx, ov, -wy, ov),
            (-ov, wx, -wy, ov),
        ]
    cams = []
    for i, (x0, x1, y0, y1) in enumerate(rects):
        cx, cy = (x0 + x1) / 2.0, (y0 + y1) / 2.0
        half_w, half_h = (x1 - x0) / 2.0, (y1 - y0) / 2.0
        focal = min(IMAGE_WIDTH / 2.0 * h / half_w, IMAGE_HEIGHT / 2.0 * h / half_h)
        cams.append(Camera(i, cx, cy, h, x0, x1, y0, y1, focal))
    return cams


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

        ball = world.ball
        bx = (ball.x + ball.vx * extrapolate_s) * 1000.0
        by = (ball.y + ball.vy * extrapolate_s) * 1000.0
        bz = ball.z * 1000.0
        if cam.sees(bx, by):
            if miss > 0.0 and rng.random() < miss:
                self.missed_detections += 1
            else:
                self._add_ball(frame, cam, rng, bx + rng.gauss(0.0, noise),
                               by + rng.gauss(0.0, noise), bz, self._confidence(rng))

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


def camera_calibration(cam: Camera) -> geom_pb.SSL_GeometryCameraCalibration:
    """Calibration of a camera looking straight down (rotation of pi about the x axis)."""
    c = geom_pb.SSL_GeometryCameraCalibration()
    c.camera_id = cam.camera_id
    c.focal_length = cam.focal
    c.principal_point_x = IMAGE_WIDTH / 2.0
    c.principal_point_y = IMAGE_HEIGHT / 2.0
    c.distortion = 0.0
    # quaternion (x, y, z, w) of a half turn about x: world -> camera
    c.q0, c.q1, c.q2, c.q3 = 1.0, 0.0, 0.0, 0.0
    # t = -R * C with R = diag(1, -1, -1)
    c.tx, c.ty, c.tz = -cam.cx, cam.cy, cam.height
    c.derived_camera_world_tx = cam.cx
    c.derived_camera_world_ty = cam.cy
    c.derived_camera_world_tz = cam.height
    c.pixel_image_width = IMAGE_WIDTH
    c.pixel_image_height = IMAGE_HEIGHT
    return c
