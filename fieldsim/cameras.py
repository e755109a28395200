"""fieldsim's cameras: where each one hangs, what it sees, how it projects the ball.

Each camera looks straight down from ``camera_height_mm`` above the centre of its rectangle
of the field (a quadrant for 4 cameras, a half for 2) extended by ``camera_overlap_mm`` past
the centre lines. Like SSL-Vision, which finds the ball's colour blob and intersects its
viewing ray with the ground, a camera reports a ball in the air at the ground point behind it
as seen from the camera (``Camera.ground_point``): so a chipped ball's detection runs ahead of
the ball, differently in each camera. The geometry packet's calibration carries each camera's
position (``derived_camera_world_tx/ty/tz``) so that a tracker can undo it.
"""

from __future__ import annotations

from dataclasses import dataclass

from fieldsim.config import SimConfig
from fieldsim.geometry import FieldGeometry
from sslpb import ssl_vision_geometry_pb2 as geom_pb

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

    def ground_point(self, x: float, y: float, z: float) -> tuple[float, float]:
        """Where the ray from the camera through the point (x, y, z) (mm) meets the ground:
        what the camera reports for a ball at that height."""
        if z <= 0.0:
            return x, y
        k = self.height / max(1.0, self.height - z)
        return self.cx + (x - self.cx) * k, self.cy + (y - self.cy) * k

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
