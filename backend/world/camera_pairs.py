"""How much two cameras disagree about where the same robot is: a calibration offset between
two cameras shows as a steady shift of one camera's detections against the other's in their
overlap (measured on robots that stand nearly still, where the cameras' unsynchronised
capture times do not matter)."""

from __future__ import annotations

from dataclasses import dataclass

#: a pair's offset is a running mean over about this many recent detections
WINDOW = 200
#: robots faster than this are left out (5 ms between two cameras' captures is 5 mm at 1 m/s)
MAX_SPEED_MM_S = 200.0


@dataclass
class PairOffset:
    """Camera b's detections minus camera a's (a < b), mm."""

    dx: float = 0.0
    dy: float = 0.0
    n: int = 0

    def add(self, dx: float, dy: float) -> None:
        self.n += 1
        k = 1.0 / min(self.n, WINDOW)
        self.dx += (dx - self.dx) * k
        self.dy += (dy - self.dy) * k


class CameraPairs:
    def __init__(self) -> None:
        self.pairs: dict[tuple[int, int], PairOffset] = {}

    def add(self, cam_a: int, xa: float, ya: float, cam_b: int, xb: float, yb: float,
            speed_mm_s: float) -> None:
        """Two cameras' detections of one robot at the same instant."""
        if cam_a == cam_b or speed_mm_s > MAX_SPEED_MM_S:
            return
        if cam_a > cam_b:
            cam_a, xa, ya, cam_b, xb, yb = cam_b, xb, yb, cam_a, xa, ya
        p = self.pairs.get((cam_a, cam_b))
        if p is None:  # (not setdefault: it would build one per call, for every robot seen twice)
            p = self.pairs[(cam_a, cam_b)] = PairOffset()
        p.add(xb - xa, yb - ya)

    def view(self) -> list[dict[str, float | int]]:
        return [{"camera_a": a, "camera_b": b, "dx_mm": p.dx, "dy_mm": p.dy, "samples": p.n}
                for (a, b), p in sorted(self.pairs.items())]
