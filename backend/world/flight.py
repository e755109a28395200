"""Chipped balls: the ball's 3D flight estimated from where the cameras see it.

A camera reports a ball in the air where its viewing ray meets the ground, behind the ball
as seen from the camera (SSL-Vision has no height for balls). With the camera at C (its
height H, from the geometry packet's ``derived_camera_world_t*``) and the detection at p on the
ground, the ball B at height z lies on that ray: ``B = p - (p - C) z / H``. A flight is a
ballistic arc: ``B(tau) = a + v tau`` on the ground plane (no rolling in the air, no drag) and
``z(tau) = vz tau - g tau^2 / 2`` from the hop's start (on the ground). Put together, every
detection gives two equations that are LINEAR in the five unknowns (a, v, vz)::

    a + v tau + vz tau (p - C) / H = p + g tau^2 (p - C) / (2 H)

so a hop is one least-squares fit, over the detections of every camera (each with its own C).

Recognition: the fit starts at a kick (``backend.world.kick``: its start time is where the
ball left the ground), or, with no kick, where a ball at rest started to move (a chip towards
the camera's nadir looks slow and may not pass the kick detector), and runs alongside the
rolling model the kick detector uses. A chip is
declared when the arc's vertical speed is at least ``min_vz_mm_s`` and its residual is well
below the rolling model's (``gain``), which is already worse than the vision noise
(``min_flat_rms_mm``): a flat kick fits the rolling model and an arc of vz ~ 0 alike. Without
camera positions nothing is estimated (the tracker then only has the kick detector).

After recognition the hop is refitted with every new detection. When its landing time has
passed, the next hop starts at the landing point with ``restitution`` times the landing
vertical speed (predicted: ``refit_bounces`` refits it on its own detections); a hop slower than
``min_bounce_mm_s`` ends the flight: the ball rolls (the kick detector's model again). The
predicted stop point follows the remaining hops (constant ground velocity) and the roll
(``decel_mm_s2``) after them.

Pure: detections in (``observe``), the kick and the time in (``update``), no clock, no I/O.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import islice

import numpy as np

from .kick import fit_rolling
from .state import KickedBall

__all__ = ["CameraPose", "Flight", "FlightConfig", "FlightTracker"]

CameraPose = tuple[float, float, float]  # x, y, height above the field (mm)


@dataclass
class FlightConfig:
    enabled: bool = True
    gravity_mm_s2: float = 9810.0
    restitution: float = 0.5  # fieldsim's chip_bounce_restitution
    min_bounce_mm_s: float = 300.0  # fieldsim's: a slower bounce ends the flight
    decel_mm_s2: float = 400.0  # rolling after the flight (the kick detector's decel_mps2)
    min_samples: int = 8  # detections of a hop before it is fitted
    min_fit_s: float = 0.05  # ... spanning at least this long
    recognise_within_s: float = 0.5  # a kick not recognised as a chip by then is flat
    # a chip the kick detector missed (its projection looked slow): a ball leaving rest is
    # tried too, from the last time it was at rest (``rest_s`` of detections within
    # ``rest_mm``) once it is ``launch_mm`` away
    launch_from_rest: bool = True
    rest_s: float = 0.1
    rest_mm: float = 15.0
    launch_mm: float = 100.0
    min_vz_mm_s: float = 500.0  # an arc slower upwards than this is not a chip
    gain: float = 0.67  # the arc's residual must be below this fraction of the rolling fit's
    min_flat_rms_mm: float = 2.5  # ... which must be worse than this (fieldsim's noise: 2 mm)
    max_flight_s: float = 4.0
    max_vz_mm_s: float = 10000.0  # faster upwards is not a kick
    max_rms_mm: float = 40.0  # a refit explaining the detections worse is not taken
    # bounces refitted on their own detections (off: predicted with the restitution; a
    # bounce's few detections, some after its real landing, made wild fits in fieldsim)
    refit_bounces: bool = False
    bounce_vz_range: tuple[float, float] = (0.3, 2.0)  # a bounce's fitted vz / the predicted
    unseen_s: float = 0.3  # no detection for this long: the flight is given up
    keep_s: float = 1.0  # detections kept


@dataclass(frozen=True, slots=True)
class Flight:
    """The hop in progress (mm, mm/s, s of capture time) and what follows it."""

    hop: int  # 0: the kick's flight, then one per bounce
    t0: float  # the hop's start, ball on the ground
    x0: float
    y0: float
    vx: float
    vy: float
    vz: float  # upwards at t0
    t_land: float
    land_x: float
    land_y: float
    stop_x: float  # after the remaining hops and the roll
    stop_y: float
    stop_t: float
    rms_mm: float  # the arc's residual (ground mm), and the rolling model's when recognised
    flat_rms_mm: float
    samples: int
    vz0: float  # the hop's vertical speed as first predicted (a bounce's refit stays near it)

    def at(self, t: float, g: float) -> tuple[float, float, float, float, float, float]:
        """x, y, z, vx, vy, vz at ``t`` (z clamped at the ground)."""
        tau = t - self.t0
        z = self.vz * tau - g * tau * tau / 2.0
        return (self.x0 + self.vx * tau, self.y0 + self.vy * tau, max(0.0, z),
                self.vx, self.vy, self.vz - g * tau)


def _arc_rows(obs: list[tuple[float, int, float, float]], t0: float,
              cams: dict[int, CameraPose], g: float) -> tuple[np.ndarray, np.ndarray]:
    """The least-squares system of the module docstring: rows x then y per detection."""
    o = np.asarray([(t - t0, px, py, *cams[cam]) for t, cam, px, py in obs])
    tau, px, py, cx, cy, h = o.T
    kx, ky = (px - cx) / h, (py - cy) / h
    n = len(obs)
    a = np.zeros((2 * n, 5))
    a[0::2, 0] = 1.0
    a[0::2, 2] = tau
    a[0::2, 4] = tau * kx
    a[1::2, 1] = 1.0
    a[1::2, 3] = tau
    a[1::2, 4] = tau * ky
    b = np.empty(2 * n)
    b[0::2] = px + g * tau * tau * kx / 2.0
    b[1::2] = py + g * tau * tau * ky / 2.0
    return a, b


def fit_arc(obs: list[tuple[float, int, float, float]], t0: float,
            cams: dict[int, CameraPose], g: float,
            start: tuple[float, float] | None = None) -> tuple[tuple[float, ...], float] | None:
    """(x0, y0, vx, vy, vz) of the arc leaving the ground at ``t0`` (at ``start`` if given: a
    bounce's landing point) that best explains the detections, and the rms residual (mm);
    None if they cannot determine it."""
    if len(obs) < 3:
        return None
    a, b = _arc_rows(obs, t0, cams, g)
    if start is not None:
        b = b - a[:, 0] * start[0] - a[:, 1] * start[1]
        a = a[:, 2:]
    k = a.shape[1]
    sol, _, rank, _ = np.linalg.lstsq(a, b, rcond=None)
    if rank < k:
        return None
    res = a @ sol - b
    rms = float(math.sqrt(float(res @ res) / max(1, len(b) - k)))
    vals = tuple(float(v) for v in sol)
    return (start + vals if start is not None else vals), rms


def _flat_rms(obs: list[tuple[float, int, float, float]], decel: float) -> float:
    pts = [(t, x, y) for t, _, x, y in obs]
    fit = fit_rolling(pts, decel)
    if fit is None:
        return math.inf
    (t0, x0, y0), w = fit
    n = math.hypot(*w)
    ux, uy = (w[0] / n, w[1] / n) if n > 1e-9 else (0.0, 0.0)
    ss = 0.0
    for t, x, y in pts:
        tau = t - t0
        ex = x0 + w[0] * tau - ux * decel * tau * tau / 2.0
        ey = y0 + w[1] * tau - uy * decel * tau * tau / 2.0
        ss += (x - ex) ** 2 + (y - ey) ** 2
    return math.sqrt(ss / max(1, 2 * len(pts) - 4))


class FlightTracker:
    """Recognises and follows a chipped ball; see the module docstring."""

    def __init__(self, config: FlightConfig | None = None) -> None:
        self.config = config or FlightConfig()
        self.cameras: dict[int, CameraPose] = {}
        self._obs: deque[tuple[float, int, float, float]] = deque(maxlen=512)
        self._n_obs = 0  # detections observed so far (the next one's number)
        #: the numbers of the detections in ``_obs`` earlier than the one before them (the
        #: cameras of one instant come in any order); none: ``_obs`` is in time order
        self._back: deque[int] = deque()
        self._flight: Flight | None = None
        self._tried_kick: float | None = None  # start time of the kick given up on
        self._last_t0 = -math.inf  # the start of the last flight (a launch is tried once)
        self._fitted_t = -math.inf  # the newest detection the last fit had: fit again after
        #: the last ``_launch`` answer in time order and what it was made of (the detections
        #: seen so far, the first recent one, the last flight's start, the parameters read):
        #: with no fit to make, ``update`` asks at every snapshot, mostly with no detection new
        self._launch_memo: tuple[tuple[float, ...], float | None] | None = None
        self.chips = 0  # flights recognised (tests, health)
        self.ended = ""  # why the last flight ended

    @property
    def flight(self) -> Flight | None:
        return self._flight

    def set_cameras(self, poses: dict[int, CameraPose]) -> None:
        """Camera positions (mm), from the geometry packet; bad ones are left out."""
        self.cameras = {c: p for c, p in poses.items()
                        if all(math.isfinite(v) for v in p) and p[2] > 500.0}

    def reset(self) -> None:
        self._obs.clear()
        self._back.clear()
        self._launch_memo = None
        self._flight = None

    def observe(self, t: float, cam: int, x: float, y: float) -> None:
        """A ball detection (mm) of camera ``cam`` taken as the ball, as the camera saw it."""
        if cam not in self.cameras:
            return
        obs = self._obs
        if obs and t < obs[-1][0]:
            self._back.append(self._n_obs)
        self._n_obs += 1
        obs.append((t, cam, x, y))
        while t - obs[0][0] > self.config.keep_s:
            obs.popleft()

    # -- geometry --------------------------------------------------------------------------

    def ground(self, t: float, cam: int, x: float, y: float) -> tuple[float, float]:
        """A detection of ``cam`` moved from the ground to under the flying ball (mm)."""
        f = self._flight
        pose = self.cameras.get(cam)
        if f is None or pose is None:
            return x, y
        z = f.at(t, self.config.gravity_mm_s2)[2]
        k = z / pose[2]
        return x - (x - pose[0]) * k, y - (y - pose[1]) * k

    def seen_at(self, t: float, cam: int) -> tuple[float, float] | None:
        """Where camera ``cam`` should see the flying ball at ``t`` (None: no flight)."""
        f = self._flight
        pose = self.cameras.get(cam)
        if f is None or pose is None:
            return None
        x, y, z, *_ = f.at(t, self.config.gravity_mm_s2)
        k = pose[2] / max(1.0, pose[2] - z)
        return pose[0] + (x - pose[0]) * k, pose[1] + (y - pose[1]) * k

    # -- per world update ------------------------------------------------------------------

    def update(self, kick: KickedBall | None, t_now: float) -> Flight | None:
        """The flight now, given the kick in progress (or None) and the world's time."""
        cfg = self.config
        if not cfg.enabled or not self.cameras:
            self._flight = None
            return None
        f = self._flight
        fresh = bool(self._obs) and self._obs[-1][0] > self._fitted_t
        if f is None:
            if not fresh:
                return None
            if kick is not None and kick.start_t != self._tried_kick:
                self._recognise(kick.start_t, t_now)
            elif kick is None and cfg.launch_from_rest:
                t0 = self._launch(t_now)
                if t0 is not None:
                    self._recognise(t0, t_now)
            return self._flight
        if not self._obs or t_now - self._obs[-1][0] > cfg.unseen_s:
            self._end("lost")
            return None
        if t_now - f.t0 > cfg.max_flight_s:
            self._end("too long")
            return None
        while f is not None and t_now > f.t_land:
            f = self._bounce(f)
        if f is None:
            self._end("rolling")
            return None
        self._flight = self._refit(f) if fresh else f
        return self._flight

    def _end(self, why: str) -> None:
        self._flight = None
        self.ended = why

    def _since(self, t0: float) -> list[tuple[float, int, float, float]]:
        return [o for o in self._obs if o[0] > t0]

    def _launch(self, t_now: float) -> float | None:
        """When a ball at rest (the detections of ``rest_s`` within ``rest_mm``) left it in
        the last ``recognise_within_s``: the last time it was there; else None."""
        cfg = self.config
        obs = self._obs
        if not obs:
            return None
        within = cfg.recognise_within_s  # (once: this runs on every new ball detection)
        back = self._back
        first = self._n_obs - len(obs)  # the number of the oldest detection kept
        while back and back[0] <= first:
            back.popleft()  # (the detection before it is gone)
        recent: Sequence[tuple[float, int, float, float]]
        if back:
            recent = [o for o in obs if t_now - o[0] <= within]
            lo = 0
        else:
            # in time order: the recent ones are the detections from the first within
            # ``within`` of t_now on (t_now - t only falls along them), found by bisection;
            # the list is made only past the common case (a ball at rest, or none launched)
            lo, hi = 0, len(obs)
            while lo < hi:
                mid = (lo + hi) // 2
                if t_now - obs[mid][0] <= within:
                    hi = mid
                else:
                    lo = mid + 1
            # the answer depends on t_now only through lo: the same detections, the same
            # first recent one and the same parameters give the same answer (the rest below
            # reads a few detections at rest, then every recent one of a launch)
            key = (self._n_obs, lo, self._last_t0, within, cfg.min_samples, cfg.launch_mm,
                   cfg.rest_s, cfg.rest_mm)
            memo = self._launch_memo
            if memo is not None and memo[0] == key:
                return memo[1]
            t0 = self._launch_from(obs, lo)
            self._launch_memo = (key, t0)
            return t0
        return self._launch_from(recent, lo)

    def _launch_from(self, recent: Sequence[tuple[float, int, float, float]],
                     lo: int) -> float | None:
        """``_launch``'s answer from the recent detections (``recent[lo:]``; ``recent`` is
        ``_obs`` itself when in time order, from its first recent one, ``lo``, on)."""
        cfg = self.config
        obs = self._obs
        back = recent is not obs
        if len(recent) - lo < cfg.min_samples:
            return None
        x0, y0 = recent[lo][2], recent[lo][3]
        if math.hypot(recent[-1][2] - x0, recent[-1][3] - y0) < cfg.launch_mm:
            return None  # still there (the common case: cheap)
        rest_s, rest_mm = cfg.rest_s, cfg.rest_mm
        if back:
            rest = [o for o in recent if o[0] - recent[0][0] <= rest_s]
            if len(rest) < 3 or rest[-1][0] - rest[0][0] < rest_s / 2:
                return None
            if any(math.hypot(o[2] - x0, o[3] - y0) > rest_mm for o in rest):
                return None
        else:
            # in time order: the detections within rest_s of the first recent one are the
            # first ones; each within rest_mm of it, or no rest (the same tests as above in
            # one loop that stops at the first one away: a ball on the move, the common case
            # here, costs a few detections read, not lists of the last half second)
            t_first = t_last = recent[lo][0]
            n = 0
            for o in islice(obs, lo, None):
                t = o[0]
                if t - t_first > rest_s:
                    break
                if math.hypot(o[2] - x0, o[3] - y0) > rest_mm:
                    return None
                n += 1
                t_last = t
            if n < 3 or t_last - t_first < rest_s / 2:
                return None
        if lo:
            recent = list(islice(obs, lo, None))
        t0 = max(o[0] for o in recent if math.hypot(o[2] - x0, o[3] - y0) <= cfg.rest_mm)
        if t0 <= self._last_t0 + cfg.rest_s:
            return None  # the launch of the flight just followed
        return t0

    def _recognise(self, t0: float, t_now: float) -> None:
        cfg = self.config
        if t_now - t0 > cfg.recognise_within_s:
            self._tried_kick = t0  # a flat kick: not tried again
            return
        obs = self._since(t0)
        if len(obs) < cfg.min_samples or obs[-1][0] - obs[0][0] < cfg.min_fit_s:
            return
        self._fitted_t = obs[-1][0]
        fit = fit_arc(obs, t0, self.cameras, cfg.gravity_mm_s2)
        if fit is None:
            return
        (x0, y0, vx, vy, vz), rms = fit
        flat = _flat_rms(obs, cfg.decel_mm_s2)
        if vz < cfg.min_vz_mm_s or flat < cfg.min_flat_rms_mm or rms > cfg.gain * flat:
            return
        if not self._believable(vz) or rms > cfg.max_rms_mm:
            return
        self.chips += 1
        self._last_t0 = t0
        self._flight = self._make(0, t0, x0, y0, vx, vy, vz, rms, flat, len(obs))

    def _refit(self, f: Flight) -> Flight:
        cfg = self.config
        if f.hop > 0 and not cfg.refit_bounces:
            return f
        obs = self._since(f.t0)
        if len(obs) < cfg.min_samples or obs[-1][0] - obs[0][0] < cfg.min_fit_s:
            return f
        self._fitted_t = obs[-1][0]
        # a bounce starts where the previous hop landed: only its velocity is fitted
        start = (f.x0, f.y0) if f.hop > 0 else None
        fit = fit_arc(obs, f.t0, self.cameras, cfg.gravity_mm_s2, start)
        if fit is None:
            return f
        (x0, y0, vx, vy, vz), rms = fit
        if f.hop == 0:
            ok = vz > 0.0 and self._believable(vz)
        else:
            lo, hi = cfg.bounce_vz_range
            ok = lo * f.vz0 <= vz <= hi * f.vz0
        if not ok or rms > cfg.max_rms_mm:
            return f  # the detections do not make a believable hop (yet): keep the prediction
        return self._make(f.hop, f.t0, x0, y0, vx, vy, vz, rms, f.flat_rms_mm, len(obs),
                          f.vz0)

    def _believable(self, vz: float) -> bool:
        """Not faster upwards than a kick, and the apex well below every camera."""
        cfg = self.config
        apex = vz * vz / (2.0 * cfg.gravity_mm_s2)
        return vz <= cfg.max_vz_mm_s and apex < 0.8 * min(p[2] for p in self.cameras.values())

    def _bounce(self, f: Flight) -> Flight | None:
        """The next hop from the landing of ``f``, or None once the ball rolls."""
        cfg = self.config
        vz = f.vz * cfg.restitution
        if vz < cfg.min_bounce_mm_s:
            return None
        return self._make(f.hop + 1, f.t_land, f.land_x, f.land_y, f.vx, f.vy, vz,
                          f.rms_mm, f.flat_rms_mm, 0, vz)

    def _make(self, hop: int, t0: float, x0: float, y0: float, vx: float, vy: float,
              vz: float, rms: float, flat: float, n: int, vz0: float | None = None) -> Flight:
        cfg = self.config
        g = cfg.gravity_mm_s2
        dt = 2.0 * vz / g
        lx, ly, t_land = x0 + vx * dt, y0 + vy * dt, t0 + dt
        # the remaining hops at the same ground velocity, then the roll
        sx, sy, st, v = lx, ly, t_land, vz * cfg.restitution
        for _ in range(64):
            if v < cfg.min_bounce_mm_s:
                break
            hop_t = 2.0 * v / g
            sx, sy, st = sx + vx * hop_t, sy + vy * hop_t, st + hop_t
            v *= cfg.restitution
        speed = math.hypot(vx, vy)
        if speed > 1e-6 and cfg.decel_mm_s2 > 0:
            d = speed * speed / (2.0 * cfg.decel_mm_s2)
            sx, sy, st = sx + vx / speed * d, sy + vy / speed * d, st + speed / cfg.decel_mm_s2
        return Flight(hop, t0, x0, y0, vx, vy, vz, t_land, lx, ly, sx, sy, st, rms, flat, n,
                      vz if vz0 is None else vz0)
