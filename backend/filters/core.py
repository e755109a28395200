"""Per-object position filters with one interface (pure, synchronous, no I/O).

Every filter takes measurements in time order: ``update(t_s, x, y) -> (x, y)`` returns the
estimate after the measurement. ``revise(x, y)`` replaces the last measurement (same instant,
e.g. a second camera's detection of the same object merged into it) without a new time step.
``predict(t_s)`` extrapolates the estimate with the filter's velocity; ``velocity()`` is in
units per second. ``reset()`` forgets everything.

Orientation goes through :class:`AngleFilter`, which unwraps the angle before any of these
filters and wraps the estimate again.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable
from itertools import islice
from typing import Protocol

from domain.angles import wrap_angle

from .adaptive import AdaptiveIMM, AdaptiveIMM1D
from .params import (
    AdaptiveParams,
    FilterKind,
    KalmanParams,
    MedianParams,
    PaperParams,
    RawParams,
)

Vec = tuple[float, float]
#: (wrap_angle's constants, for the angle filter's step)
_PI, _TAU = math.pi, 2.0 * math.pi


class PositionFilter(Protocol):
    kind: FilterKind

    @property
    def t_last(self) -> float | None: ...

    def update(self, t_s: float, x: float, y: float) -> Vec: ...

    def revise(self, x: float, y: float) -> Vec: ...

    def estimate(self) -> Vec | None: ...

    def velocity(self) -> Vec: ...

    def predict(self, t_s: float) -> Vec | None: ...

    def reset(self) -> None: ...


def line_sums(pts: Iterable[tuple[float, float, float]],
              n: int) -> tuple[float, float, float, float, float, float]:
    """Of ``n`` points (t, x, y): the means tm, xm, ym and the sums of (t - tm) ** 2,
    (t - tm) * (x - xm) and (t - tm) * (y - ym), the least-squares slopes' parts (VelocityFit,
    the kick detector). The sums as ``sum(... for p in pts)`` made them, in the same order (a
    float sum in another order changes bits: 0 + the first, then each in order; ** 2, not
    d * d: the same pow), in two plain loops (six generators cost twice as much)."""
    tm = xm = ym = 0.0
    for t, x, y in pts:
        tm += t
        xm += x
        ym += y
    tm /= n
    xm /= n
    ym /= n
    stt = sx = sy = 0.0
    for t, x, y in pts:
        d = t - tm
        stt += d ** 2
        sx += d * (x - xm)
        sy += d * (y - ym)
    return tm, xm, ym, stt, sx, sy


class VelocityFit:
    """Velocity as the slope of a least-squares line through the points of the last
    ``window_s`` seconds (at least the last two points).

    The same sums as ``sum(... for p in sel)`` in the same order (a float sum in another order
    changes bits), in two plain loops (six generators cost twice as much). While the times
    never went back (the world model's always), the window is the points from ``_lo`` on (a
    point once out of it stays out: the newest time only grows), found without a pass over
    them all; and a velocity is computed once per point added or replaced."""

    __slots__ = ("_lo", "_mono", "_pts", "_v", "_w")

    def __init__(self, window_s: float = 0.1, max_points: int = 48) -> None:
        self._w = window_s
        self._pts: deque[tuple[float, float, float]] = deque(maxlen=max_points)
        #: the times never went back since the last clear (NaN counts as going back)
        self._mono = True
        #: while they did not: no point before this index is in the window
        self._lo = 0
        self._v: Vec | None = None  # the velocity, until the points change

    @property
    def window_s(self) -> float:
        return self._w  # (fixed: the window's start and the velocity are kept)

    def add(self, t: float, x: float, y: float) -> None:
        pts = self._pts
        if pts:
            if not t >= pts[-1][0]:
                self._mono = False
            if len(pts) == pts.maxlen and self._lo:  # the oldest goes
                self._lo -= 1
        pts.append((t, x, y))
        self._v = None

    def replace_last(self, x: float, y: float) -> None:
        if self._pts:
            t = self._pts[-1][0]
            self._pts[-1] = (t, x, y)
            self._v = None

    def clear(self) -> None:
        self._pts.clear()
        self._mono = True
        self._lo = 0
        self._v = None

    def velocity(self) -> Vec:
        v = self._v
        if v is not None:
            return v
        pts = self._pts
        n = len(pts)
        if n < 2:
            return (0.0, 0.0)
        t_end = pts[-1][0]
        w = self._w
        sel: Iterable[tuple[float, float, float]]
        if self._mono:
            # the window is a suffix: the times do not decrease, nor does t_end - t along it
            lo = self._lo
            while lo < n and not t_end - pts[lo][0] <= w:
                lo += 1
            self._lo = lo
            if n - lo < 2:
                sel, n = (pts[-2], pts[-1]), 2
            elif lo:
                sel = list(islice(pts, lo, None))
                n -= lo
            else:
                sel = pts
        else:
            sel = [p for p in pts if t_end - p[0] <= w]
            if len(sel) < 2:
                sel = [pts[-2], pts[-1]]
            n = len(sel)
        _, _, _, stt, sx, sy = line_sums(sel, n)
        v = (0.0, 0.0) if stt < 1e-9 else (sx / stt, sy / stt)
        self._v = v
        return v


class MedianWeighted:
    """Median of the last ``window`` measurements per coordinate, then
    ``est = (1 - w_new) * est_prev + w_new * median`` (the paper's filter). Re-initialises to
    the median after a gap longer than ``gap_s`` or when the median is more than ``jump`` away
    from the estimate. ``window=1, w_new=1`` is no filter; ``w_new=1`` is the median alone."""

    __slots__ = (
        "_est",
        "_hx",
        "_hy",
        "_last_median",
        "_prev_est",
        "_t",
        "_vel",
        "gap_s",
        "jump",
        "kind",
        "w_new",
        "window",
    )

    def __init__(self, kind: FilterKind, window: int, w_new: float, gap_s: float, jump: float,
                 velocity_window_s: float) -> None:
        self.kind = kind
        self.window = window
        self.w_new = w_new
        self.gap_s = gap_s
        self.jump = jump
        # the last measurements, per coordinate (each sorted as it is for its median)
        self._hx: deque[float] = deque(maxlen=window)
        self._hy: deque[float] = deque(maxlen=window)
        self._est: Vec | None = None
        self._prev_est: Vec | None = None
        self._t: float | None = None
        self._vel = VelocityFit(velocity_window_s)
        self._last_median: Vec | None = None

    @property
    def t_last(self) -> float | None:
        return self._t

    @property
    def last_median(self) -> Vec | None:
        return self._last_median

    def reset(self) -> None:
        self._hx.clear()
        self._hy.clear()
        self._est = self._prev_est = self._t = self._last_median = None
        self._vel.clear()

    def _step(self, prev: Vec | None) -> Vec:
        hx = self._hx
        n = len(hx)
        if n == 1:
            m = (hx[0], self._hy[0])
        else:  # the median of each coordinate
            sx, sy = sorted(hx), sorted(self._hy)
            h = n // 2
            m = ((sx[h], sy[h]) if n % 2
                 else (0.5 * (sx[h - 1] + sx[h]), 0.5 * (sy[h - 1] + sy[h])))
        self._last_median = m
        if prev is None or self.w_new >= 1.0:
            est = m
        else:
            dx, dy = m[0] - prev[0], m[1] - prev[1]
            if dx * dx + dy * dy > self.jump * self.jump:
                est = m
            else:
                w = self.w_new
                est = (prev[0] + w * dx, prev[1] + w * dy)
        self._est = est
        return est

    def update(self, t_s: float, x: float, y: float) -> Vec:
        if self._t is not None and t_s - self._t > self.gap_s:
            self.reset()
        self._hx.append(x)
        self._hy.append(y)
        self._prev_est = prev = self._est
        t = self._t
        self._t = t_s if t is None or t_s > t else t  # (max(t, t_s))
        est = self._step(prev)
        m = self._last_median
        assert m is not None
        self._vel.add(t_s, m[0], m[1])
        return est

    def revise(self, x: float, y: float) -> Vec:
        if not self._hx or self._t is None:
            return self.update(0.0, x, y)
        self._hx[-1] = x
        self._hy[-1] = y
        est = self._step(self._prev_est)
        m = self._last_median
        assert m is not None
        self._vel.replace_last(m[0], m[1])
        return est

    def estimate(self) -> Vec | None:
        return self._est

    def velocity(self) -> Vec:
        return self._vel.velocity()

    def predict(self, t_s: float) -> Vec | None:
        if self._est is None or self._t is None:
            return None
        vx, vy = self.velocity()
        dt = t_s - self._t
        return (self._est[0] + vx * dt, self._est[1] + vy * dt)


class RawFilter(MedianWeighted):
    """No filtering: the estimate is the latest measurement."""

    def __init__(self, params: RawParams | None = None) -> None:
        p = params or RawParams()
        super().__init__("raw", 1, 1.0, math.inf, math.inf, p.velocity_window_s)


class MedianFilter(MedianWeighted):
    """The median of the last N measurements per coordinate."""

    def __init__(self, params: MedianParams | None = None) -> None:
        p = params or MedianParams()
        super().__init__("median", p.window, 1.0, p.gap_s, math.inf, p.velocity_window_s)


class PaperFilter(MedianWeighted):
    """URoboRus 2022: median of the last N, then the weighted average with the previous
    estimate; re-initialised after a gap or a jump."""

    def __init__(self, params: PaperParams | None = None, angle: bool = False) -> None:
        p = params or PaperParams()
        super().__init__("paper", p.window, p.w_new, p.gap_s,
                         p.jump_rad if angle else p.jump_mm, p.velocity_window_s)


class KalmanCV:
    """Constant-velocity Kalman filter, state (x, y, vx, vy), white-noise acceleration of std
    ``accel_noise`` (units/s^2), position measurements of std ``meas_noise``. The axes are
    independent (diagonal noise), so each is a 2x2 filter; this is exact for this model.
    Optional gate: a measurement farther than ``gate`` from the prediction is not used; after
    5 rejections in a row the filter re-initialises at the measurement.

    The state is one flat tuple per step (x: p, v, Ppp, Ppv, Pvv, then y the same), the
    arithmetic unrolled: it runs for every robot a camera sees, 600 frames a second.
    ``one_axis`` (the orientation, whose y is always 0): only x is filtered; y stays 0."""

    __slots__ = (
        "_n_rej",
        "_prior",
        "_s",
        "_t",
        "gap_s",
        "gate",
        "init_speed_std",
        "kind",
        "one_axis",
        "q",
        "r",
        "rejected",
    )

    def __init__(self, accel_noise: float = 4000.0, meas_noise: float = 3.0, gate: float = 0.0,
                 gap_s: float = 1.0, init_speed_std: float = 3000.0,
                 one_axis: bool = False) -> None:
        self.kind: FilterKind = "kalman"
        self.q = accel_noise * accel_noise
        self.r = meas_noise * meas_noise
        self.gate = gate
        self.gap_s = gap_s
        self.init_speed_std = init_speed_std
        self.one_axis = one_axis
        self.rejected = 0
        # x: p, v, Ppp, Ppv, Pvv; then the same for y
        self._s: tuple[float, ...] | None = None
        self._prior: tuple[float, ...] | None = None
        self._t: float | None = None
        self._n_rej = 0

    @classmethod
    def from_params(cls, params: KalmanParams | None = None, angle: bool = False) -> KalmanCV:
        p = params or KalmanParams()
        if angle:
            return cls(p.angle_accel_noise_rad_s2, p.angle_meas_noise_rad, 0.0, p.gap_s, 10.0,
                       one_axis=True)
        return cls(p.accel_noise_mm_s2, p.meas_noise_mm, p.gate_mm, p.gap_s)

    @property
    def t_last(self) -> float | None:
        return self._t

    def reset(self) -> None:
        self._s = self._prior = self._t = None
        self._n_rej = 0

    def _init(self, t: float, x: float, y: float) -> Vec:
        v0 = self.init_speed_std ** 2
        r = self.r
        self._s = (x, 0.0, r, 0.0, v0, 0.0 if self.one_axis else y, 0.0, r, 0.0, v0)
        self._prior = None
        self._t = t
        self._n_rej = 0
        return (x, self._s[5])

    def _correct(self, pri: tuple[float, ...], x: float, y: float) -> tuple[float, ...]:
        r = self.r
        p, v, a, b, c, py, vy, ay, by, cy = pri
        s = a + r
        k0, k1 = a / s, b / s
        inn = x - p
        if self.one_axis:
            return (p + k0 * inn, v + k1 * inn, (1 - k0) * a, (1 - k0) * b, c - k1 * b,
                    py, vy, ay, by, cy)
        sy = ay + r
        k0y, k1y = ay / sy, by / sy
        inny = y - py
        return (p + k0 * inn, v + k1 * inn, (1 - k0) * a, (1 - k0) * b, c - k1 * b,
                py + k0y * inny, vy + k1y * inny, (1 - k0y) * ay, (1 - k0y) * by, cy - k1y * by)

    def update(self, t_s: float, x: float, y: float) -> Vec:
        st, t0 = self._s, self._t
        if st is None or t0 is None or t_s - t0 > self.gap_s:
            return self._init(t_s, x, y)
        dt = max(0.0, t_s - t0)
        q = self.q
        qa, qb, qc = q * dt ** 4 / 4, q * dt ** 3 / 2, q * dt * dt
        p, v, a, b, c, py, vy, ay, by, cy = st
        if self.one_axis:
            pri = (p + v * dt, v, a + 2 * dt * b + dt * dt * c + qa, b + dt * c + qb, c + qc,
                   py, vy, ay, by, cy)
        else:
            pri = (p + v * dt, v, a + 2 * dt * b + dt * dt * c + qa, b + dt * c + qb, c + qc,
                   py + vy * dt, vy, ay + 2 * dt * by + dt * dt * cy + qa, by + dt * cy + qb,
                   cy + qc)
        self._t = t_s
        if self.gate > 0:
            ex, ey = x - pri[0], y - pri[5]
            if ex * ex + ey * ey > self.gate * self.gate:
                self._n_rej += 1
                self.rejected += 1
                if self._n_rej >= 5:
                    return self._init(t_s, x, y)
                self._s = pri
                self._prior = None
                return (pri[0], pri[5])
        self._n_rej = 0
        self._prior = pri
        s = self._s = self._correct(pri, x, y)
        return (s[0], s[5])

    def revise(self, x: float, y: float) -> Vec:
        if self._s is None or self._t is None:
            return self.update(0.0, x, y)
        if self._prior is None:  # the last step initialised (or gated): start from this one
            return self._init(self._t, x, y)
        s = self._s = self._correct(self._prior, x, y)
        return (s[0], s[5])

    def estimate(self) -> Vec | None:
        s = self._s
        if s is None:
            return None
        return (s[0], s[5])

    def velocity(self) -> Vec:
        s = self._s
        if s is None:
            return (0.0, 0.0)
        return (s[1], s[6])

    def predict(self, t_s: float) -> Vec | None:
        s = self._s
        if s is None or self._t is None:
            return None
        dt = t_s - self._t
        return (s[0] + s[1] * dt, s[5] + s[6] * dt)


class AngleFilter:
    """Orientation through any position filter: the measurement is unwrapped against the
    previous one (so a turn through +-pi is continuous), filtered as the x coordinate, and the
    estimate wrapped back to [-pi, pi)."""

    __slots__ = ("_forgets", "_u", "_u_before", "inner")

    def __init__(self, inner: PositionFilter) -> None:
        self.inner = inner
        #: the inner filter may have no estimate while it has a time (forgot the object);
        #: this module's filters have both or neither, so they are not asked (per frame)
        self._forgets = type(inner) not in _KEEP_BOTH
        self._u: float | None = None  # unwrapped last measurement
        self._u_before: float | None = None  # unwrapped measurement before the last

    @property
    def kind(self) -> FilterKind:
        return self.inner.kind

    @property
    def t_last(self) -> float | None:
        return self.inner.t_last

    def reset(self) -> None:
        self.inner.reset()
        self._u = self._u_before = None

    def _unwrap(self, ref: float | None, a: float) -> float:
        return a if ref is None else ref + wrap_angle(a - ref)

    # update, revise and estimate run for every robot in every camera frame: wrap_angle and
    # _unwrap are written out in them (the same arithmetic and the same guard against the
    # modulo rounding up to 2 pi: a call costs more than the expression)

    def update(self, t_s: float, a: float) -> float:
        inner = self.inner
        ref = self._u
        if (ref is not None and self._forgets and inner.estimate() is None
                and inner.t_last is not None):
            ref = None  # the inner filter forgot the object: no unwrapping against it
        self._u_before = ref
        u = a if ref is None else ref + ((a - ref + _PI) % _TAU - _PI)
        self._u = u
        w = (inner.update(t_s, u, 0.0)[0] + _PI) % _TAU - _PI
        return -_PI if w == _PI else w

    def revise(self, a: float) -> float:
        ref = self._u_before
        u = a if ref is None else ref + ((a - ref + _PI) % _TAU - _PI)
        self._u = u
        w = (self.inner.revise(u, 0.0)[0] + _PI) % _TAU - _PI
        return -_PI if w == _PI else w

    def estimate(self) -> float | None:
        e = self.inner.estimate()
        if e is None:
            return None
        w = (e[0] + _PI) % _TAU - _PI
        return -_PI if w == _PI else w

    def rate(self) -> float:
        return self.inner.velocity()[0]

    def predict(self, t_s: float) -> float | None:
        p = self.inner.predict(t_s)
        if p is None:
            return None
        w = (p[0] + _PI) % _TAU - _PI
        return -_PI if w == _PI else w


#: the filters whose ``estimate()`` is None exactly while their ``t_last`` is (before the
#: first measurement and after a reset)
_KEEP_BOTH: frozenset[type] = frozenset({
    MedianWeighted, RawFilter, MedianFilter, PaperFilter, KalmanCV, AdaptiveIMM, AdaptiveIMM1D})


AnyParams = RawParams | MedianParams | PaperParams | KalmanParams | AdaptiveParams


def make_filter(kind: FilterKind, params: AnyParams | None = None,
                angle: bool = False) -> PositionFilter:
    """A new filter of ``kind``; ``params`` must be that kind's model (None: defaults).
    ``angle=True`` picks the orientation parameters (rad) where a kind has them."""
    if kind == "adaptive":
        ap = params if isinstance(params, AdaptiveParams) else None
        return AdaptiveIMM1D(ap) if angle else AdaptiveIMM(ap)
    if kind == "raw":
        return RawFilter(params if isinstance(params, RawParams) else None)
    if kind == "median":
        return MedianFilter(params if isinstance(params, MedianParams) else None)
    if kind == "paper":
        return PaperFilter(params if isinstance(params, PaperParams) else None, angle=angle)
    return KalmanCV.from_params(params if isinstance(params, KalmanParams) else None, angle)
