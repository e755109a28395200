"""Merges detection frames from several unsynchronised cameras into one filtered world state.

One object per robot (team, id) and one ball. Per object:

* Detections by several cameras at the same instant (capture times within
  ``merge_window_s``) are one measurement, their mean (circular mean for the orientation); a
  detection at a new instant is a new filter step. Out-of-order older frames are ignored.
* The measurement goes through the object's filter (``backend.filters``: raw, median, paper,
  kalman, adaptive (the default); chosen per object class and per robot by
  :class:`FilterSettings`). The state carries
  both the filtered value (``x``, ``y``, ``orientation``) and the latest merged measurement
  (``raw_x``, ``raw_y``, ``raw_orientation``), and the filter's velocity.
* Times: a frame's capture time is checked against the relay's receive clock, per camera
  (:mod:`backend.world.clock`), and mapped onto it; a frame far from its camera's clock is
  dropped and counted, a camera whose clock jumped is re-synchronised. So no time from the
  wire becomes "the latest time" alone, and ``WorldState.receive_time_ns`` is the receive time
  of the newest frame that was merged: the age of the world by this machine's clock.
* Sanity: a camera id above ``max_camera_id``, objects outside the field plus a margin
  (``field_half_length_mm``/``field_half_width_mm``, set from the geometry packet) and objects
  beyond ``max_objects`` in one frame are dropped and counted (``rejected``, by reason).
* An object not seen for ``predict_after_s`` is extrapolated with its velocity
  (``predicted``), after ``visible_timeout_s`` it is ``lost`` (not visible, frozen, velocity zero),
  after ``drop_timeout_s`` removed.

Ball association among false detections: detections inside a robot's footprint (a false "ball
on top of a robot") are rejected; the remaining candidates are compared with the ball's
prediction from its recent raw track, and the nearest one within the distance the ball can
have travelled at ``ball_max_speed_mm_s`` is taken. Candidates not taken feed hypotheses; a
hypothesis confirmed by ``ball_recover_count`` consistent detections while the tracked ball has
not been seen for ``ball_recover_after_s`` replaces it (teleport, fast kick, wrong start).

Several balls: a ball seen while the tracked one keeps being seen never replaces it; a
hypothesis confirmed by ``other_ball_confirm_count`` detections, farther than
``other_ball_min_distance_mm`` from the ball, is reported in ``WorldState.other_balls`` (a
second ball left on the field) until it is not seen for ``ball_hypothesis_timeout_s``.

Chipped balls (``backend.world.flight``): with the camera positions known (``set_cameras``,
from the geometry packet) a kick whose detections fit a ballistic arc better than a roll is a
flight; while it lasts, each camera's detection is moved from the ground to under the ball
before it is associated and merged (the cameras see a flying ball at different places), and
the ball's x, y, z, vx, vy, vz are the arc's. Between a kick's start and its recognition the
cameras of one instant may disagree by up to ``ball_camera_disparity_mm``.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, replace
from typing import cast

from backend.filters.core import AngleFilter, PositionFilter, VelocityFit, make_filter
from backend.filters.params import FilterKind, FilterSettings
from domain.field import DIVISION_A
from domain.rules import ROBOT_RADIUS_MM

from .camera_pairs import CameraPairs
from .clock import CameraClocks, ClockConfig
from .flight import CameraPose, FlightConfig, FlightTracker
from .kick import KickConfig, KickDetector
from .state import (
    BallState,
    CameraFrame,
    KickedBall,
    OtherBall,
    RawBall,
    RobotState,
    Team,
    WorldState,
)


@dataclass
class WorldModelConfig:
    # detections of different cameras this close in capture time are one measurement
    merge_window_s: float = 0.005
    camera_window_s: float = 0.05  # a camera counts as seeing an object for this long
    predict_after_s: float = 0.05  # not seen for longer: position extrapolated (predicted)
    visible_timeout_s: float = 0.2  # not seen for longer: lost (visible = False)
    drop_timeout_s: float = 3.0  # not seen for longer: removed
    camera_timeout_s: float = 1.0
    history: int = 12  # merged measurements kept per object (re-initialising a new filter)
    robot_radius_mm: float = ROBOT_RADIUS_MM  # a ball detection this near a robot centre is false
    ball_max_speed_mm_s: float = 10000.0  # faster than this is not the ball
    ball_gate_slack_mm: float = 60.0  # noise allowance added to the travel distance
    ball_assoc_window_s: float = 0.1  # unseen longer: only a confirmed hypothesis is taken
    ball_recover_count: int = 3  # consistent detections that confirm a hypothesis
    ball_recover_after_s: float = 0.05  # tracked ball unseen this long before switching
    ball_hypothesis_timeout_s: float = 0.1  # a hypothesis not confirmed again is forgotten
    ball_max_hypotheses: int = 16
    ball_camera_disparity_mm: float = 400.0  # a kick's rising ball: cameras of one instant
    other_ball_confirm_count: int = 10  # consistent detections before another ball is reported
    other_ball_min_distance_mm: float = 300.0  # nearer to the ball: not another ball
    velocity_smoothing: float = 0.3  # unused since the filters give velocities (kept for params)
    # sanity limits on what a frame may carry (the rest is dropped and counted)
    max_camera_id: int = 63
    max_objects: int = 64  # balls, and robots per team, in one frame
    # objects beyond the field plus its boundary plus this are not on the field (mm)
    field_margin_mm: float = 1000.0
    # the larger field (division A) until a geometry packet says otherwise: before it comes, no
    # real detection is dropped as off the field, whichever division plays
    field_half_length_mm: float = DIVISION_A.half_length
    field_half_width_mm: float = DIVISION_A.half_width
    field_boundary_mm: float = 300.0
    clock: ClockConfig = field(default_factory=ClockConfig)
    kicks: KickConfig = field(default_factory=KickConfig)
    flight: FlightConfig = field(default_factory=FlightConfig)


#: one merged measurement: [t, x, y, orientation] (a list, not an object: one is made per
#: detection at a new instant, and the instant's is changed in place when a camera adds to it)
_Meas = list[float]


@dataclass
class _Track:
    kind: FilterKind
    key: object  # (kind, params) the filters were built from
    pos: PositionFilter
    ang: AngleFilter | None
    t_meas: float = -math.inf  # capture time of the latest measurement instant
    raw: _Meas = field(default_factory=lambda: [0.0, 0.0, 0.0, 0.0])
    # running sums of the detections at the current instant (ss and sc, of the orientation's
    # sine and cosine, from the second detection on: few objects get one)
    n: int = 0
    sx: float = 0.0
    sy: float = 0.0
    ss: float = 0.0
    sc: float = 0.0
    instant_cams: set[int] = field(default_factory=set)
    cam_seen: dict[int, float] = field(default_factory=dict)
    history: deque[_Meas] = field(default_factory=deque)
    #: the velocity of the raw measurements (the ball's association reads it; robots have none:
    #: nothing reads theirs, and it cost two calls per detection)
    raw_vel: VelocityFit | None = None
    #: the object's state as the last snapshot built it, while it holds (no measurement or
    #: filter change since, and not predicted): eight cameras see a robot in few frames, and
    #: the ball in a frame of few. A robot's track holds a RobotState, the ball's a BallState
    snap: RobotState | BallState | None = None


@dataclass
class _Hypothesis:
    x: float
    y: float
    t: float
    count: int
    points: list[tuple[float, float, float]]
    cams: dict[int, float] = field(default_factory=dict)  # camera -> capture time seen


class WorldModel:
    def __init__(self, config: WorldModelConfig | None = None,
                 filters: FilterSettings | None = None) -> None:
        self.config = config or WorldModelConfig()
        self._settings = filters or FilterSettings()
        self._robots: dict[tuple[Team, int], _Track] = {}
        self._order: list[tuple[Team, int]] = []  # the robots' keys sorted (snapshot order)
        #: the last snapshot's robots while every one of them was seen within
        #: ``predict_after_s`` (None otherwise): the next snapshot copies it and builds only
        #: the robots a camera saw since (``_dirty``), when all are still that fresh
        self._states: list[RobotState] | None = None
        self._index: dict[tuple[Team, int], int] = {}  # key -> its place in _order
        self._dirty: list[tuple[Team, int]] = []  # robots measured since the last snapshot
        #: at most the oldest ``t_meas`` of the robots (it only grows until one is added)
        self._oldest = -math.inf
        self._ball: _Track | None = None
        self._hyps: list[_Hypothesis] = []
        self._cameras: dict[int, CameraFrame] = {}
        self._cam_order: list[int] = []  # the cameras' ids sorted
        #: how far apart two cameras see the same robots (calibration offsets), per pair
        self.camera_pairs = CameraPairs()
        self._t_latest = 0.0
        self._recv_latest = 0
        self.clocks = CameraClocks(self.config.clock)
        self.kicks = KickDetector(self.config.kicks)
        self.kicks_enabled = True
        self._kick_fed_t = -math.inf  # the newest ball measurement the kick detector has
        self.flight = FlightTracker(self.config.flight)
        self._chip_kick: KickedBall | None = None  # the kick of the flight in progress
        #: frames and objects dropped, by reason ("time out of range", "bad camera id",
        #: "object out of field", "too many objects")
        self.rejected: dict[str, int] = {}
        self.last_rejection = ""
        self.ball_rejected_on_robot = 0  # counters for health/experiments
        self.ball_rejected_gate = 0
        self.ball_recoveries = 0

    # -- filters ---------------------------------------------------------------------------

    @property
    def settings(self) -> FilterSettings:
        return self._settings

    def _new_track(self, kind: FilterKind, with_angle: bool) -> _Track:
        params = self._settings.params_for(kind)
        ang = AngleFilter(make_filter(kind, params, angle=True)) if with_angle else None
        return _Track(kind, (kind, params), make_filter(kind, params), ang,
                      history=deque(maxlen=self.config.history),
                      raw_vel=None if with_angle else VelocityFit(0.1, 16))

    def configure(self, settings: FilterSettings) -> None:
        """Use new filter settings from now on. An object whose filter kind or parameters
        change gets a new filter, initialised from its latest measurements."""
        self._settings = settings
        for (team, rid), tr in self._robots.items():
            self._rebuild(tr, settings.robot_kind(team, rid))
        if self._ball is not None:
            self._rebuild(self._ball, settings.ball)

    def _rebuild(self, tr: _Track, kind: FilterKind) -> None:
        params = self._settings.params_for(kind)
        if tr.key == (kind, params):
            return
        tr.kind, tr.key = kind, (kind, params)
        tr.snap = None
        self._states = None
        tr.pos = make_filter(kind, params)
        tr.ang = AngleFilter(make_filter(kind, params, angle=True)) if tr.ang else None
        for t, x, y, o in tr.history:
            tr.pos.update(t, x, y)
            if tr.ang is not None:
                tr.ang.update(t, o)

    # -- measurements ----------------------------------------------------------------------

    def _measure(self, tr: _Track, t: float, cam: int, x: float, y: float, o: float) -> bool:
        """Feed one detection; False if it was ignored (older than the latest instant)."""
        w = self.config.merge_window_s
        if -w <= t - tr.t_meas <= w and tr.n > 0 and cam not in tr.instant_cams:
            tr.snap = None
            # another camera at the same instant: one measurement, the mean (the sums in
            # locals: this runs for every object each further camera sees)
            n, ang, sx, sy, raw = tr.n, tr.ang, tr.sx, tr.sy, tr.raw
            pair = n == 1 and ang is not None  # a robot seen by a second camera: compare
            if pair:
                (first,) = tr.instant_cams
                fx, fy = sx, sy
            if n == 1:  # (raw: the first detection still)
                ss, sc = math.sin(raw[3]) + math.sin(o), math.cos(raw[3]) + math.cos(o)
            else:
                ss, sc = tr.ss + math.sin(o), tr.sc + math.cos(o)
            tr.instant_cams.add(cam)
            n += 1
            sx += x
            sy += y
            tr.n, tr.sx, tr.sy, tr.ss, tr.sc = n, sx, sy, ss, sc
            mx, my = sx / n, sy / n
            mo = math.atan2(ss, sc)
            pos = tr.pos
            pos.revise(mx, my)
            if pair:  # the speed of the merged measurement (the first camera's alone may
                # have looked like a jump to the filter)
                vx, vy = pos.velocity()
                self.camera_pairs.add(first, fx, fy, cam, x, y, math.hypot(vx, vy))
            if ang is not None:
                ang.revise(mo)
            # the instant's measurement (also the history's last: changed in place, not
            # rebuilt)
            raw[1], raw[2], raw[3] = mx, my, mo
            if tr.raw_vel is not None:
                tr.raw_vel.replace_last(mx, my)
            tr.cam_seen[cam] = t
            return True
        if t <= tr.t_meas:
            return False  # older than (or a duplicate of) the latest instant
        tr.snap = None
        tr.t_meas = t
        tr.n, tr.sx, tr.sy = 1, x, y
        tr.instant_cams = {cam}
        tr.pos.update(t, x, y)
        if tr.ang is not None:
            tr.ang.update(t, o)
        tr.raw = raw = [t, x, y, o]
        tr.history.append(raw)
        if tr.raw_vel is not None:
            tr.raw_vel.add(t, x, y)
        tr.cam_seen[cam] = t
        return True

    def _reject(self, reason: str, detail: str, n: int = 1) -> None:
        self.rejected[reason] = self.rejected.get(reason, 0) + n
        self.last_rejection = f"{reason}: {detail}"

    def set_field(self, half_length_mm: float, half_width_mm: float,
                  boundary_mm: float) -> None:
        """The field from the geometry packet (objects beyond it plus the margin are dropped).
        Nonsense (non-finite, not positive) is ignored: the previous field stays."""
        vals = (half_length_mm, half_width_mm, boundary_mm)
        if not all(math.isfinite(v) for v in vals) or half_length_mm <= 0 or half_width_mm <= 0:
            return
        c = self.config
        c.field_half_length_mm, c.field_half_width_mm = half_length_mm, half_width_mm
        c.field_boundary_mm = max(0.0, boundary_mm)

    def set_cameras(self, poses: dict[int, CameraPose]) -> None:
        """Camera positions (x, y, height, mm) from the geometry packet's calibration."""
        self.flight.set_cameras(poses)

    def _on_field(self, x: float, y: float) -> bool:
        c = self.config
        extra = c.field_boundary_mm + c.field_margin_mm
        return abs(x) <= c.field_half_length_mm + extra and abs(y) <= c.field_half_width_mm + extra

    def update(self, frame: CameraFrame) -> bool:
        """Merge one camera frame. False if the whole frame was dropped (counted in
        ``rejected``): its camera id or its capture time cannot be right."""
        cfg = self.config
        if not 0 <= frame.camera_id <= cfg.max_camera_id:
            self._reject("bad camera id", f"camera {frame.camera_id}")
            return False
        verdict = self.clocks.check(frame.camera_id, frame.t_capture, frame.receive_time_ns)
        if verdict.t_local is None:
            self._reject("time out of range",
                         f"camera {frame.camera_id} frame {frame.frame_number}: capture time "
                         f"{verdict.skew_s:+.3f} s from its clock")
            return False
        t = verdict.t_local
        if len(frame.robots) > 2 * cfg.max_objects:
            self._reject("too many objects", f"camera {frame.camera_id}: "
                         f"{len(frame.robots)} robots")
            frame = replace(frame, robots=frame.robots[:2 * cfg.max_objects])
        if verdict.resynced:
            self.last_rejection = (f"camera {frame.camera_id}: clock re-synchronised "
                                   f"(offset {self.clocks.offsets()[frame.camera_id]:+.3f} s)")
        if t != frame.t_capture:  # (not dataclasses.replace: 600 frames a second)
            frame = CameraFrame(frame.camera_id, frame.frame_number, t, frame.t_sent,
                                frame.receive_time_ns, frame.balls, frame.robots)
        self._cameras[frame.camera_id] = frame
        if t > self._t_latest:
            self._t_latest = t
        # the world's age by this machine's clock: the newest arrival merged (a frame a camera
        # captured a moment before another one's still brings news)
        self._recv_latest = max(self._recv_latest, frame.receive_time_ns)
        seen: set[tuple[Team, int]] = set()
        per_team = {"blue": 0, "yellow": 0}
        extra = cfg.field_boundary_mm + cfg.field_margin_mm  # _on_field, inlined
        lx, ly = cfg.field_half_length_mm + extra, cfg.field_half_width_mm + extra
        robots = self._robots
        cam, max_objects = frame.camera_id, cfg.max_objects
        measure, dirty = self._measure, self._dirty  # (per detection: locals)
        for det in frame.robots:
            team = det.team
            key = (team, det.id)
            if key in seen:  # a duplicate id in one frame: keep the first
                continue
            x, y = det.x, det.y
            if not (abs(x) <= lx and abs(y) <= ly):
                self._reject("object out of field", f"{team} {det.id} at ({x:.0f}, {y:.0f})")
                continue
            n = per_team[team] + 1
            per_team[team] = n
            if n > max_objects:
                self._reject("too many objects", f"camera {cam}: more than "
                             f"{max_objects} {team} robots")
                break
            seen.add(key)
            tr = robots.get(key)
            if tr is None:
                tr = self._new_track(self._settings.robot_kind(team, det.id), True)
                robots[key] = tr
            if tr.snap is None:
                measure(tr, t, cam, x, y, det.orientation)
            elif measure(tr, t, cam, x, y, det.orientation):
                dirty.append(key)  # (its snapshot state was reset: built again)
        self._update_ball(frame)
        return True

    # -- ball ------------------------------------------------------------------------------

    def _on_robot(self, b: RawBall, frame: CameraFrame) -> bool:
        r2 = self.config.robot_radius_mm ** 2
        bx, by = b.x, b.y
        for d in frame.robots:
            if (bx - d.x) ** 2 + (by - d.y) ** 2 <= r2:
                return True
        lost = self.config.visible_timeout_s
        t = frame.t_capture
        for tr in self._robots.values():  # (every robot, for every ball detection)
            if t - tr.t_meas <= lost:
                e = tr.pos.estimate()
                if e is not None and (bx - e[0]) ** 2 + (by - e[1]) ** 2 <= r2:
                    return True
        return False

    def _gate(self, dt: float) -> float:
        return self.config.ball_gate_slack_mm + self.config.ball_max_speed_mm_s * max(0.0, dt)

    def _update_ball(self, frame: CameraFrame) -> None:
        if not frame.balls:
            return
        cfg = self.config
        t, cam = frame.t_capture, frame.camera_id
        cands: list[RawBall] = []
        balls = frame.balls
        if len(balls) > cfg.max_objects:
            self._reject("too many objects", f"camera {cam}: {len(balls)} balls")
            balls = balls[:cfg.max_objects]
        for b in balls:
            if not self._on_field(b.x, b.y):
                self._reject("object out of field", f"ball at ({b.x:.0f}, {b.y:.0f})")
            elif self._on_robot(b, frame):
                self.ball_rejected_on_robot += 1
            else:
                cands.append(b)
        if not cands:
            return
        bt = self._ball
        if bt is None:  # nothing known: start from the most confident detection
            best = max(cands, key=lambda b: b.confidence)
            bt = self._new_track(self._settings.ball, False)
            self._ball = bt
            self._measure(bt, t, cam, best.x, best.y, 0.0)
            self._hyps.clear()
            return
        dt = t - bt.t_meas
        if dt < -cfg.merge_window_s or (dt <= 0 and cam in bt.instant_cams):
            return  # an older frame than the ball's latest measurement
        same_instant = abs(dt) <= cfg.merge_window_s and cam not in bt.instant_cams
        flying = self.flight.flight is not None
        # a flying ball: each camera's detection moved to under the ball
        ground = [self.flight.ground(t, cam, b.x, b.y) if flying else (b.x, b.y)
                  for b in cands]
        if same_instant:
            ref: tuple[float, float] = (bt.raw[1], bt.raw[2])
            gate = cfg.ball_gate_slack_mm
            if not flying and self.kicks.kick is not None:
                gate += cfg.ball_camera_disparity_mm  # perhaps rising, not yet recognised
        else:
            vx, vy = bt.raw_vel.velocity() if bt.raw_vel is not None else (0.0, 0.0)
            ref = (bt.raw[1] + vx * dt, bt.raw[2] + vy * dt)
            gate = self._gate(dt) if dt <= cfg.ball_assoc_window_s else -1.0
        best_i, best_d2 = -1, gate * gate if gate >= 0 else -1.0
        for i, (gx, gy) in enumerate(ground):
            d2 = (gx - ref[0]) ** 2 + (gy - ref[1]) ** 2
            if d2 <= best_d2:
                best_i, best_d2 = i, d2
        if best_i >= 0:
            b = cands[best_i]
            if self._measure(bt, t, cam, ground[best_i][0], ground[best_i][1], 0.0):
                self.flight.observe(t, cam, b.x, b.y)
            rest = cands[:best_i] + cands[best_i + 1:]
        else:
            rest = cands
        self.ball_rejected_gate += len(rest)
        self._hypothesise(rest, t, cam)
        if best_i < 0 and dt >= cfg.ball_recover_after_s:
            confirmed = [h for h in self._hyps
                         if h.t == t and h.count >= cfg.ball_recover_count]
            if confirmed:
                h = max(confirmed, key=lambda h: h.count)
                self._jump(h)

    def _hypothesise(self, cands: list[RawBall], t: float, cam: int) -> None:
        cfg = self.config
        self._hyps = [h for h in self._hyps if t - h.t <= cfg.ball_hypothesis_timeout_s]
        for b in cands:
            match: _Hypothesis | None = None
            best = math.inf
            for h in self._hyps:
                if h.points[-1][0] == t:
                    continue  # one detection per hypothesis and instant
                d = math.hypot(b.x - h.x, b.y - h.y)
                if d <= self._gate(t - h.t) and d < best:
                    match, best = h, d
            if match is None:
                if len(self._hyps) < cfg.ball_max_hypotheses:
                    self._hyps.append(_Hypothesis(b.x, b.y, t, 1, [(t, b.x, b.y)], {cam: t}))
            else:
                match.x, match.y, match.t = b.x, b.y, t
                match.cams[cam] = t
                match.count += 1
                match.points.append((t, b.x, b.y))
                del match.points[:-8]

    def _jump(self, h: _Hypothesis) -> None:
        """The ball is where a confirmed hypothesis says: a new track from its detections."""
        old = self._ball
        bt = self._new_track(self._settings.ball, False)
        if old is not None:
            bt.cam_seen = old.cam_seen
        for tp, xp, yp in h.points:
            self._measure(bt, tp, -1 - len(bt.history), xp, yp, 0.0)
        self._ball = bt
        self._hyps = [k for k in self._hyps if k is not h]
        self.ball_recoveries += 1

    # -- output ----------------------------------------------------------------------------

    def _where(self, tr: _Track, t_now: float) -> tuple[float, float, float, float, bool, bool]:
        """x, y, vx, vy, predicted, lost."""
        cfg = self.config
        age = t_now - tr.t_meas
        est = tr.pos.estimate() or (tr.raw[1], tr.raw[2])
        vx, vy = tr.pos.velocity()
        if age <= cfg.predict_after_s:
            return est[0], est[1], vx, vy, False, False
        if age <= cfg.visible_timeout_s:
            p = tr.pos.predict(t_now) or est
            return p[0], p[1], vx, vy, True, False
        p = tr.pos.predict(tr.t_meas + cfg.visible_timeout_s) or est
        return p[0], p[1], 0.0, 0.0, False, True

    def _cams(self, tr: _Track) -> tuple[int, ...]:
        """The cameras that saw the object within ``camera_window_s`` of its latest
        measurement. The others are forgotten here: ``t_meas`` only grows, so they would not
        count again before they see it again (and a robot seen by one camera then takes the
        snapshot's short way)."""
        w = self.config.camera_window_s
        t = tr.t_meas
        seen = tr.cam_seen
        # (plain loops, no comprehensions: each is a call of its own, and this runs for every
        # robot state built while two cameras see it)
        stale: list[int] | None = None
        for c, tc in seen.items():
            if t - tc > w:
                if stale is None:
                    stale = [c]
                else:
                    stale.append(c)
        if stale is not None:
            for c in stale:
                del seen[c]
        cams = sorted(seen)
        if cams and cams[0] < 0:  # (a ball's recovered detections: no camera of their own)
            return tuple([c for c in cams if c >= 0])
        return tuple(cams)

    def _seen_state(self, key: tuple[Team, int], tr: _Track) -> RobotState:
        """A robot seen within ``predict_after_s``: its state, kept in ``tr.snap`` until a
        camera sees it again (eight cameras see a robot in few frames)."""
        _, rx, ry, ro = tr.raw
        est = tr.pos.estimate() or (rx, ry)
        vx, vy = tr.pos.velocity()
        o, omega = ro, 0.0
        ang = tr.ang
        if ang is not None:
            eo = ang.estimate()
            if eo is not None:
                o = eo
            omega = ang.rate()
        seen = tr.cam_seen
        if len(seen) == 1:
            ((c, _),) = seen.items()  # seen at t_meas: inside the camera window
            seen_by: tuple[int, ...] = (c,) if c >= 0 else ()
        else:
            seen_by = self._cams(tr)
        state = RobotState(key[0], key[1], est[0], est[1], o, vx, vy, omega, tr.t_meas,
                           True, seen_by, rx, ry, ro, False, False, tr.kind)
        tr.snap = state
        return state

    def _robot_states(self, t_now: float) -> list[RobotState]:
        """Every robot's state at ``t_now``, in key order; robots not seen for
        ``drop_timeout_s`` are removed."""
        cfg = self.config
        predict_after = cfg.predict_after_s
        robots = self._robots
        dirty = self._dirty
        self._dirty = []
        states = self._states
        if states is not None and len(self._order) == len(robots):
            # the last snapshot's robots were all seen recently and none came since: when
            # they all still are (none predicted, lost or dropped), only the robots seen since
            # change (the same states as the loop below, which reuses the others' too)
            fresh = min(predict_after, cfg.drop_timeout_s)
            if t_now - self._oldest > fresh:
                self._oldest = min(tr.t_meas for tr in robots.values())
            if t_now - self._oldest <= fresh:
                states = states.copy()
                index = self._index
                for key in dirty:
                    states[index[key]] = self._seen_state(key, robots[key])
                self._states = states
                return states
        out: list[RobotState] = []
        resorted = len(self._order) != len(robots)
        if resorted:  # a robot came or went: sort again
            self._order = sorted(robots)
        dropped = False
        all_seen = True
        oldest = math.inf
        for key in self._order:
            tr = robots[key]
            age = t_now - tr.t_meas
            if age > cfg.drop_timeout_s:
                del robots[key]
                dropped = True
                continue
            if tr.t_meas < oldest:
                oldest = tr.t_meas
            if age <= predict_after:
                if tr.snap is not None:
                    out.append(cast(RobotState, tr.snap))  # unchanged since the last one
                else:
                    out.append(self._seen_state(key, tr))
                continue
            all_seen = False
            x, y, vx, vy, predicted, lost = self._where(tr, t_now)
            ang = tr.ang
            _, rx, ry, ro = tr.raw
            o = ro
            omega = 0.0
            if ang is not None:
                eo = ang.estimate()
                o = eo if eo is not None else ro
                if not lost:
                    omega = ang.rate()
                if predicted:
                    po = ang.predict(t_now)
                    o = po if po is not None else o
            state = RobotState(
                key[0], key[1], x, y, o, vx, vy, omega, tr.t_meas, not lost, self._cams(tr),
                raw_x=rx, raw_y=ry, raw_orientation=ro,
                predicted=predicted, lost=lost, filter=tr.kind)
            tr.snap = None
            out.append(state)
        if dropped:
            self._order = sorted(robots)
        if dropped or resorted:
            self._index = {k: i for i, k in enumerate(self._order)}
        self._oldest = oldest
        self._states = out if all_seen and not dropped else None
        return out

    def snapshot(self, now: float | None = None) -> WorldState:
        """The current world. ``now`` (Unix s) defaults to the newest capture time.

        Built once per world tick, from what changed: an object's state is built when a camera
        measured it since the last snapshot (or while it is predicted), the others' are the
        last snapshot's. Why not only when read: the kick detector, the flight estimate and
        the drops must follow every tick; and each robot's state is already built once per
        measurement (about 90 a second at 8 cameras x 75 Hz), while the readers together
        (tracked vision up to 100 Hz, the views 60, the strategy 20, control every tick) read
        more often than that: built when read, the states would be built about as often."""
        cfg = self.config
        t_now = self._t_latest if now is None else now
        robots = self._robot_states(t_now)
        ball = None
        if self._ball is not None:
            tr = self._ball
            age = t_now - tr.t_meas
            if age > cfg.drop_timeout_s:
                self._ball = None
            elif age <= cfg.predict_after_s and tr.snap is not None:
                ball = cast(BallState, tr.snap)  # seen lately, nothing new since
            else:
                x, y, vx, vy, predicted, lost = self._where(tr, t_now)
                ball = BallState(x, y, vx, vy, tr.t_meas, not lost, self._cams(tr),
                                 raw_x=tr.raw[1], raw_y=tr.raw[2], predicted=predicted,
                                 lost=lost, filter=tr.kind)
                # (seen lately: the state holds until the ball is measured again, as a
                # robot's; predicted or lost, it moves with t_now)
                tr.snap = ball if age <= cfg.predict_after_s else None
        frames = self._cameras
        if len(self._cam_order) != len(frames):  # a camera came (none ever goes)
            self._cam_order = sorted(frames)
        cam_timeout = cfg.camera_timeout_s
        cams = tuple([f for f in map(frames.__getitem__, self._cam_order)
                      if t_now - f.t_capture <= cam_timeout])
        new: list[tuple[float, float, float]] = []
        if self._ball is not None:
            # the measurements the kick detector has not had (the history's newest: its
            # times only grow)
            fed = self._kick_fed_t
            for mt, mx, my, _ in reversed(self._ball.history):
                if mt <= fed:
                    break
                new.append((mt, mx, my))
            if new:
                new.reverse()
                self._kick_fed_t = new[-1][0]
        if self.kicks_enabled:
            kick = self.kicks.update(new, ball, robots)
        else:
            self.kicks.reset()
            kick = None
        flight = self.flight.update(kick, t_now) if ball is not None else None
        if flight is None:
            self._chip_kick = None
        elif ball is not None:
            x, y, z, vx, vy, vz = flight.at(t_now, self.flight.config.gravity_mm_s2)
            ball = replace(ball, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz, flying=True)
            # the chip's kick lasts as long as its flight (the detector, seeing the estimate
            # jump from the cameras' ground points to under the ball, may have ended it)
            if self._chip_kick is None and kick is not None:
                self._chip_kick = replace(kick, chip=True, vx=flight.vx, vy=flight.vy,
                                          vz=flight.vz)
            elif self._chip_kick is None and flight.hop == 0:
                # launched from rest, missed by the kick detector: a kick of no known robot
                self._chip_kick = KickedBall(None, flight.x0, flight.y0, flight.t0, flight.vx,
                                             flight.vy, flight.stop_x, flight.stop_y,
                                             flight.stop_t, chip=True, vz=flight.vz)
            if self._chip_kick is not None:
                kick = replace(self._chip_kick, stop_x=flight.stop_x, stop_y=flight.stop_y,
                               stop_t=flight.stop_t, land_x=flight.land_x,
                               land_y=flight.land_y, land_t=flight.t_land)
                if flight.hop == 0:
                    kick = replace(kick, vx=flight.vx, vy=flight.vy, vz=flight.vz)
                    self._chip_kick = kick
        return WorldState(self._t_latest, self._recv_latest, ball, tuple(robots), cams,
                          kicked_ball=kick, other_balls=self._other_balls(ball, t_now),
                          flying_balls=bool(self.flight.cameras) and self.flight.config.enabled,
                          index=self._index)

    def _other_balls(self, ball: BallState | None, t_now: float) -> tuple[OtherBall, ...]:
        """Confirmed hypotheses away from the ball: other balls on the field."""
        cfg = self.config
        out = []
        for h in self._hyps:
            if h.count < cfg.other_ball_confirm_count:
                continue
            if t_now - h.t > cfg.ball_hypothesis_timeout_s:
                continue
            if ball is not None and not ball.lost and math.hypot(
                    h.x - ball.x, h.y - ball.y) < cfg.other_ball_min_distance_mm:
                continue
            cams = tuple(sorted(c for c, tc in h.cams.items()
                                if c >= 0 and h.t - tc <= cfg.camera_window_s))
            out.append(OtherBall(h.x, h.y, h.t, cams, h.count))
        out.sort(key=lambda o: (o.x, o.y))
        return tuple(out)
