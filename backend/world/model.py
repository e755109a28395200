"""Merges detection frames from several unsynchronised cameras into one world state.

One object per robot (team, id) and one ball. Cameras overlap: detections of the same object
by several cameras at about the same capture time are averaged. This is the plain merge of
the end-to-end loop; filtering proper plugs in behind ``update``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .state import BallState, CameraFrame, RawBall, RobotState, Team, WorldState


@dataclass
class WorldModelConfig:
    merge_window_s: float = 0.025  # detections this close in capture time are one observation
    visible_timeout_s: float = 0.25  # not seen for this long: visible = False
    drop_timeout_s: float = 3.0  # not seen for this long: removed
    velocity_smoothing: float = 0.3  # weight of a new finite-difference velocity
    ball_max_jump_mm: float = 1000.0  # farther from the prediction: take the most confident
    camera_timeout_s: float = 1.0


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


@dataclass
class _Obs:
    t: float
    x: float
    y: float
    orientation: float
    camera: int


class WorldModel:
    def __init__(self, config: WorldModelConfig | None = None) -> None:
        self.config = config or WorldModelConfig()
        self._robot_obs: dict[tuple[Team, int], dict[int, _Obs]] = {}
        self._robots: dict[tuple[Team, int], RobotState] = {}
        self._ball: BallState | None = None
        self._cameras: dict[int, CameraFrame] = {}
        self._t_latest = 0.0
        self._recv_latest = 0

    def update(self, frame: CameraFrame) -> None:
        """Merge one camera frame."""
        cfg = self.config
        self._cameras[frame.camera_id] = frame
        if frame.t_capture > self._t_latest:
            self._t_latest = frame.t_capture
            self._recv_latest = frame.receive_time_ns
        seen: set[tuple[Team, int]] = set()
        for det in frame.robots:
            key = (det.team, det.id)
            if key in seen:  # a duplicate id in one frame: keep the first
                continue
            seen.add(key)
            obs = self._robot_obs.setdefault(key, {})
            obs[frame.camera_id] = _Obs(frame.t_capture, det.x, det.y, det.orientation,
                                        frame.camera_id)
            recent = [o for o in obs.values() if frame.t_capture - o.t <= cfg.merge_window_s]
            x = sum(o.x for o in recent) / len(recent)
            y = sum(o.y for o in recent) / len(recent)
            ori = math.atan2(sum(math.sin(o.orientation) for o in recent),
                             sum(math.cos(o.orientation) for o in recent))
            cams = tuple(sorted(o.camera for o in recent))
            prev = self._robots.get(key)
            if prev is None:
                self._robots[key] = RobotState(det.team, det.id, x, y, ori, t_seen=frame.t_capture,
                                               cameras=cams)
                continue
            dt = frame.t_capture - prev.t_seen
            if dt > 0.004:
                a = cfg.velocity_smoothing
                prev.vx = (1 - a) * prev.vx + a * (x - prev.x) / dt
                prev.vy = (1 - a) * prev.vy + a * (y - prev.y) / dt
                prev.omega = (1 - a) * prev.omega + a * _wrap(ori - prev.orientation) / dt
                if dt > 0.5:  # after a long gap the old velocity means nothing
                    prev.vx = prev.vy = prev.omega = 0.0
            if dt >= 0 or len(recent) > 1:
                prev.x, prev.y, prev.orientation = x, y, ori
                prev.t_seen = max(prev.t_seen, frame.t_capture)
                prev.cameras = cams
            prev.visible = True
        self._update_ball(frame)

    def _update_ball(self, frame: CameraFrame) -> None:
        if not frame.balls:
            return
        ball = self._ball
        best: RawBall
        if ball is None or frame.t_capture - ball.t_seen > self.config.visible_timeout_s:
            best = max(frame.balls, key=lambda b: b.confidence)
        else:
            # predicted position, then the nearest detection
            dt = max(0.0, frame.t_capture - ball.t_seen)
            px, py = ball.x + ball.vx * dt, ball.y + ball.vy * dt
            best = min(frame.balls, key=lambda b: (b.x - px) ** 2 + (b.y - py) ** 2)
            if math.hypot(best.x - px, best.y - py) > self.config.ball_max_jump_mm:
                best = max(frame.balls, key=lambda b: b.confidence)
        if ball is None:
            self._ball = BallState(best.x, best.y, t_seen=frame.t_capture,
                                   cameras=(frame.camera_id,))
            return
        dt = frame.t_capture - ball.t_seen
        if dt < -0.004:  # an older frame from another camera: don't move backwards in time
            return
        same_moment = (
            abs(dt) <= self.config.merge_window_s / 2
            and frame.camera_id not in ball.cameras
            and math.hypot(best.x - ball.x, best.y - ball.y) < 100
        )
        if same_moment:
            n = len(ball.cameras)
            ball.x = (ball.x * n + best.x) / (n + 1)
            ball.y = (ball.y * n + best.y) / (n + 1)
            ball.cameras = (*ball.cameras, frame.camera_id)
            return
        if dt > 0.004:
            a = self.config.velocity_smoothing
            ball.vx = (1 - a) * ball.vx + a * (best.x - ball.x) / dt
            ball.vy = (1 - a) * ball.vy + a * (best.y - ball.y) / dt
            if dt > 0.5:
                ball.vx = ball.vy = 0.0
        ball.x, ball.y = best.x, best.y
        ball.t_seen = max(ball.t_seen, frame.t_capture)
        ball.cameras = (frame.camera_id,)
        ball.visible = True

    def snapshot(self, now: float | None = None) -> WorldState:
        """The current world. ``now`` (Unix s) defaults to the newest capture time."""
        cfg = self.config
        t_now = self._t_latest if now is None else now
        robots: list[RobotState] = []
        for key in sorted(self._robots):
            r = self._robots[key]
            age = t_now - r.t_seen
            if age > cfg.drop_timeout_s:
                del self._robots[key]
                self._robot_obs.pop(key, None)
                continue
            r.visible = age <= cfg.visible_timeout_s
            robots.append(RobotState(r.team, r.id, r.x, r.y, r.orientation, r.vx, r.vy, r.omega,
                                     r.t_seen, r.visible, r.cameras))
        ball = None
        if self._ball is not None:
            b = self._ball
            age = t_now - b.t_seen
            if age > cfg.drop_timeout_s:
                self._ball = None
            else:
                b.visible = age <= cfg.visible_timeout_s
                ball = BallState(b.x, b.y, b.vx, b.vy, b.t_seen, b.visible, b.cameras)
        cams = tuple(
            self._cameras[c] for c in sorted(self._cameras)
            if t_now - self._cameras[c].t_capture <= cfg.camera_timeout_s
        )
        return WorldState(self._t_latest, self._recv_latest, ball, tuple(robots), cams)
