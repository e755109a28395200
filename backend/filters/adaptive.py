"""The default filter: a still/moving interacting multiple model that learns its noise.

Why this design (docs/experiments/filters/README.md has the numbers): a Kalman filter tuned for
one noise level is wrong at the others (3 mm assumed, 20 mm real: worse than no filter), and the
paper's filter is precise on a still object but lags a moving one. No single (q, r) pair fits a
resting ball and a kicked one, so this filter carries two motion models and lets the data pick:

* **still**: the position is constant (a tiny random walk); its estimate is the running mean,
  the most precise thing a still object allows, and its velocity is exactly zero;
* **moving**: constant velocity with white acceleration (a robot driving, a rolling ball).

They are mixed as an IMM (Blom & Bar-Shalom): per step the model probabilities follow a Markov
chain, each model starts from the mix of both, and the output is the probability-weighted
combination. Measurement noise ``r`` is estimated from the data: the innovations of accepted
measurements, minus the model's own prediction variance, averaged over a sliding horizon (the
Mehra / Sage-Husa estimator); the outlier rate is estimated the same way from the gate's verdicts.

Outliers and maneuvers (a kick, a bounce) both show up as a measurement far outside the gate. They
are told apart by physics and by the data: a measurement farther than the object could have
travelled (``max_speed``) is an outlier; a reachable one is a maneuver at once when no outliers
have been seen lately, otherwise when the next measurement confirms it (one frame of delay, only
in outlier-ridden data). A run of consistent far measurements (the ball placed elsewhere)
re-initialises the filter.

Plain float arithmetic per axis (no numpy): for a 2-state filter CPython's float operations are
several times faster than small matrices, and this runs for every object in every camera frame.
"""

from __future__ import annotations

import math
from operator import attrgetter

from .params import AdaptiveParams, FilterKind

Vec = tuple[float, float]

#: everything that changes per step (saved before a step so that ``revise`` can redo it)
_STATE = (
    "_t", "_ta", "mu", "r", "q_m", "_age", "outlier_rate", "rejected", "n_far",
    "sx", "sy", "spx", "spy", "mx", "my", "mvx", "mvy", "mpx", "mpy", "mbx", "mby", "mcx", "mcy",
    "_h", "_pend", "_far", "_far0", "_backup",
)
_get_state = attrgetter(*_STATE)


class AdaptiveIMM:
    """Still/moving IMM with estimated noise and robust gating (see the module doc), 2-D.

    State per model and axis: still ``x, P``; moving ``x, v`` with covariance ``P = [[p, b],
    [b, c]]``. ``mu`` is the probability of "still"."""

    __slots__ = (*_STATE, "_prev", "gap_s", "gate2", "horizon", "kind", "max_speed", "q_max",
                 "q_min", "q_s", "r_max", "r_min", "rho_accept", "switch_ms", "switch_sm",
                 "q_down", "q_rate")

    dims = 2

    def __init__(self, params: AdaptiveParams | None = None, angle: bool = False) -> None:
        p = params or AdaptiveParams()
        self.kind: FilterKind = "adaptive"
        if angle:
            r0, rmin, rmax = p.angle_init_noise_rad, p.angle_min_noise_rad, p.angle_max_noise_rad
            q0, qmin, qmax = (p.angle_accel_init_rad_s2, p.angle_accel_min_rad_s2,
                              p.angle_accel_max_rad_s2)
            self.q_s = p.angle_still_drift_rad_s ** 2
            self.max_speed = p.angle_max_rate_rad_s
        else:
            r0, rmin, rmax = p.init_noise_mm, p.min_noise_mm, p.max_noise_mm
            q0, qmin, qmax = p.accel_init_mm_s2, p.accel_min_mm_s2, p.accel_max_mm_s2
            self.q_s = p.still_drift_mm_s ** 2
            self.max_speed = p.max_speed_mm_s
        self.r = r0 * r0
        self.r_min, self.r_max = rmin * rmin, rmax * rmax
        self.q_m = q0 * q0
        self.q_min, self.q_max = qmin * qmin, qmax * qmax
        self.q_rate = p.accel_adapt_rate
        self.q_down = 1.0 + p.accel_shrink_bias
        self.gate2 = p.gate_sigma ** 2
        self.gap_s = p.gap_s
        self.horizon = float(p.noise_horizon)
        self.switch_sm = p.still_to_moving_per_s
        self.switch_ms = p.moving_to_still_per_s
        self.rho_accept = p.outlier_rate_trust
        self.rejected = 0
        self.outlier_rate = 0.0
        self.n_far = 0
        self._t: float | None = None
        self._ta = 0.0  # time of the last measurement used
        self._age = 0.0  # samples in the noise average
        self.mu = 0.5
        self.sx = self.sy = self.spx = self.spy = 0.0
        self.mx = self.my = self.mvx = self.mvy = 0.0
        self.mpx = self.mpy = self.mbx = self.mby = self.mcx = self.mcy = 0.0
        # the last two measurements used (t, x, y, t, x, y), for the noise estimate
        self._h: tuple[float, ...] = ()
        self._pend: tuple[float, float, float] | None = None  # a reachable jump (t, x, y)
        self._far: tuple[float, float, float] | None = None  # last unreachable measurement
        self._far0 = (0.0, 0.0, 0.0)  # the first of a run of unreachable ones
        self._backup: tuple[object, ...] | None = None  # the track before a jump
        self._prev: tuple[object, ...] | None = None  # the state before the last update

    # -- state -------------------------------------------------------------------------------

    @property
    def t_last(self) -> float | None:
        return self._t

    def reset(self) -> None:
        self._t = None
        self._prev = self._pend = self._far = self._backup = None
        self._h = ()
        self._age = 0.0
        self.n_far = 0

    def _save(self) -> tuple[object, ...]:
        return _get_state(self)  # type: ignore[no-any-return]

    def _load(self, st: tuple[object, ...]) -> None:
        for k, v in zip(_STATE, st, strict=True):
            setattr(self, k, v)

    def _init(self, t: float, x: float, y: float, v: Vec = (0.0, 0.0), mu: float = 0.5,
              pvv: float | None = None) -> Vec:
        r = self.r
        pv = pvv if pvv is not None else self.max_speed ** 2 / 4
        self.sx, self.sy, self.spx, self.spy = x, y, r, r
        self.mx, self.my, self.mvx, self.mvy = x, y, v[0], v[1]
        self.mpx = self.mpy = r
        self.mbx = self.mby = 0.0
        self.mcx = self.mcy = pv
        self.mu = mu
        self._t = self._ta = t
        self._h = (t, x, y)
        self._pend = self._far = self._backup = None
        self.n_far = 0
        return (x, y)

    # -- the step ----------------------------------------------------------------------------

    def update(self, t_s: float, x: float, y: float) -> Vec:
        self._prev = _get_state(self)
        return self._step(t_s, x, y)

    def revise(self, x: float, y: float) -> Vec:
        if self._prev is None or self._t is None:
            return self.update(0.0 if self._t is None else self._t, x, y)
        t = self._t
        self._load(self._prev)
        return self._step(t, x, y)

    def _mixing(self, dt: float) -> tuple[float, float, float, float]:
        """Prior probability of still, and the mixing weights (still's share of the still
        model's start, still's share of the moving model's start)."""
        ms = self.mu
        a = self.switch_sm * dt
        b = self.switch_ms * dt
        if a > 0.5:
            a = 0.5
        if b > 0.5:
            b = 0.5
        cs = (1.0 - a) * ms + b * (1.0 - ms)
        cm = 1.0 - cs
        ws_s = (1.0 - a) * ms / cs if cs > 1e-12 else 0.0
        wm_s = a * ms / cm if cm > 1e-12 else 0.0
        return cs, cm, ws_s, wm_s

    def _step(self, t: float, zx: float, zy: float) -> Vec:
        t0 = self._t
        if t0 is None or t - t0 > self.gap_s:
            return self._init(t, zx, zy)
        dt = t - t0 if t > t0 else 0.0
        self._t = t
        r = self.r
        cs, cm, ws_s, wm_s = self._mixing(dt)
        ws_m = 1.0 - ws_s
        wm_m = 1.0 - wm_s
        qs = self.q_s * dt
        q = self.q_m
        dt2 = dt * dt
        q11 = q * dt2 * dt2 * 0.25
        q12 = q * dt2 * dt * 0.5
        q22 = q * dt2
        # -- x: mix, predict, innovate
        xs, ps, xm, vm, pa, pb, pc = (self.sx, self.spx, self.mx, self.mvx, self.mpx, self.mbx,
                                      self.mcx)
        x0 = ws_s * xs + ws_m * xm
        es = xs - x0
        em = xm - x0
        p0x = ws_s * (ps + es * es) + ws_m * (pa + em * em) + qs
        x1 = wm_s * xs + wm_m * xm
        v1x = wm_m * vm
        es = xs - x1
        em = xm - x1
        ev = vm - v1x
        a1 = wm_s * (ps + es * es) + wm_m * (pa + em * em)
        b1 = wm_m * (pb + em * ev) - wm_s * es * v1x
        c1 = wm_s * v1x * v1x + wm_m * (pc + ev * ev)
        xpx = x1 + v1x * dt
        apx = a1 + 2.0 * dt * b1 + dt2 * c1 + q11
        bpx = b1 + dt * c1 + q12
        cpx = c1 + q22
        x0x = x0
        nsx = zx - x0
        nmx = zx - xpx
        ssx = p0x + r
        smx = apx + r
        # -- y
        xs, ps, xm, vm, pa, pb, pc = (self.sy, self.spy, self.my, self.mvy, self.mpy, self.mby,
                                      self.mcy)
        x0 = ws_s * xs + ws_m * xm
        es = xs - x0
        em = xm - x0
        p0y = ws_s * (ps + es * es) + ws_m * (pa + em * em) + qs
        x1 = wm_s * xs + wm_m * xm
        v1y = wm_m * vm
        es = xs - x1
        em = xm - x1
        ev = vm - v1y
        a1 = wm_s * (ps + es * es) + wm_m * (pa + em * em)
        b1 = wm_m * (pb + em * ev) - wm_s * es * v1y
        c1 = wm_s * v1y * v1y + wm_m * (pc + ev * ev)
        xpy = x1 + v1y * dt
        apy = a1 + 2.0 * dt * b1 + dt2 * c1 + q11
        bpy = b1 + dt * c1 + q12
        cpy = c1 + q22
        x0y = x0
        nsy = zy - x0
        nmy = zy - xpy
        ssy = p0y + r
        smy = apy + r
        d2s = nsx * nsx / ssx + nsy * nsy / ssy
        d2m = nmx * nmx / smx + nmy * nmy / smy
        if d2s > self.gate2 and d2m > self.gate2:
            pred = (x0x, x0y, p0x, p0y, xpx, xpy, v1x, v1y, apx, apy, bpx, bpy, cpx, cpy)
            return self._rejected(t, dt, zx, zy, pred, cs)
        # -- corrections
        g = p0x / ssx
        self.sx = x0x + g * nsx
        self.spx = (1.0 - g) * p0x
        g = p0y / ssy
        self.sy = x0y + g * nsy
        self.spy = (1.0 - g) * p0y
        k0 = apx / smx
        k1 = bpx / smx
        self.mx = xpx + k0 * nmx
        self.mvx = v1x + k1 * nmx
        self.mpx = (1.0 - k0) * apx
        self.mbx = (1.0 - k0) * bpx
        self.mcx = cpx - k1 * bpx
        k0 = apy / smy
        k1 = bpy / smy
        self.my = xpy + k0 * nmy
        self.mvy = v1y + k1 * nmy
        self.mpy = (1.0 - k0) * apy
        self.mby = (1.0 - k0) * bpy
        self.mcy = cpy - k1 * bpy
        # -- model probabilities: Gaussian likelihood ratio still / moving
        e = 0.5 * (d2m - d2s)
        lr = math.exp(e if e < 700.0 else 700.0) * math.sqrt(smx * smy / (ssx * ssy))
        mu = cs * lr / (cs * lr + cm)
        self.mu = 1e-6 if mu < 1e-6 else (1.0 - 1e-6 if mu > 1.0 - 1e-6 else mu)
        self._accepted(t, d2m * 0.5, zx, zy)
        return (self.mu * self.sx + (1.0 - self.mu) * self.mx,
                self.mu * self.sy + (1.0 - self.mu) * self.my)

    def _accepted(self, t: float, nis: float, zx: float, zy: float) -> None:
        """Bookkeeping after a measurement was used: outlier rate, q and r estimates."""
        if self._pend is not None or self._far is not None or self._backup is not None:
            self._pend = self._far = self._backup = None
        self._ta = t
        self.n_far = 0
        self.outlier_rate -= self.outlier_rate / self.horizon
        # process noise: grow when the moving model's innovations are larger than it predicts
        # (normalised innovation squared > 1), shrink slowly otherwise: the smallest q the data
        # agree with
        q = self.q_m * math.exp(self.q_rate * ((nis if nis < 20.0 else 20.0) - self.q_down))
        self.q_m = self.q_min if q < self.q_min else (self.q_max if q > self.q_max else q)
        # measurement noise from the second differences of the measurements used (independent
        # of the motion model, so a wrong q does not leak into r): z_k - z_k-1 - rho (z_k-1 -
        # z_k-2) has variance (1 + (1 + rho)^2 + rho^2) r while the motion is smooth
        h = self._h
        if len(h) == 6:
            t1, x1, y1, t2, x2, y2 = h
            if t1 > t2 and t > t1:
                rho = (t - t1) / (t1 - t2)
                ex = zx - x1 - rho * (x1 - x2)
                ey = zy - y1 - rho * (y1 - y2)
                r = self.r
                e2 = 0.5 * (ex * ex + ey * ey) if self.dims == 2 else ex * ex
                sample = e2 / (1.0 + (1.0 + rho) ** 2 + rho * rho)
                if sample > 16.0 * r:
                    sample = 16.0 * r
                self._age += 1.0
                r += (sample - r) / (self._age + 1.0 if self._age < self.horizon
                                     else self.horizon)
                self.r = self.r_min if r < self.r_min else (self.r_max if r > self.r_max else r)
            self._h = (t, zx, zy, t1, x1, y1)
        else:
            self._h = (t, zx, zy, *h[:3])

    def _rejected(self, t: float, dt: float, zx: float, zy: float, pred: tuple[float, ...],
                  cs: float) -> Vec:
        """A measurement outside both models' gates: an outlier, a maneuver or a new place."""
        self.rejected += 1
        bk = self._backup
        if bk is not None:
            # the last step re-initialised on a jump; if this measurement fits the track from
            # before that jump, the jump was an outlier after all: go back to that track
            self._backup = None
            cur = _get_state(self)
            n_rej = self.rejected
            self._load(bk)
            self.rejected = n_rej
            out = self._step(t, zx, zy)
            if self.rejected == n_rej:
                return out
            self._load(cur)
            self.rejected = n_rej
        ex, ey = self.estimate_fast()
        dx, dy = zx - ex, zy - ey
        lim0 = math.sqrt(self.gate2 * self.r)
        reach = self.max_speed * (t - self._ta) + lim0
        pend = self._pend
        confirmed = False
        v = (0.0, 0.0)
        if pend is not None and t > pend[0]:  # does it continue the last reachable jump?
            px, py = zx - pend[1], zy - pend[2]
            tp = t - pend[0]
            lim = self.max_speed * tp + lim0
            # a maneuver continues away from where the object was, in about the same direction
            ox, oy = pend[1] - ex, pend[2] - ey
            along = px * ox + py * oy
            if (px * px + py * py <= lim * lim and along > 0.0
                    and along * along >= 0.5 * (px * px + py * py) * (ox * ox + oy * oy)):
                confirmed = True
                v = (px / tp, py / tp)
        if confirmed or dx * dx + dy * dy <= reach * reach:
            if not confirmed and dt > 0:
                v = (dx / dt, dy / dt)
            if confirmed or self.outlier_rate < self.rho_accept:
                dv2 = v[0] * v[0] + v[1] * v[1]
                self._set_pred(pred, cs)
                bk = _get_state(self)
                self._init(t, zx, zy, v, mu=1e-3, pvv=dv2 + self.r / max(dt, 1e-3) ** 2)
                self._backup = bk
                return (zx, zy)
            self._pend = (t, zx, zy)
        else:
            # a run of far measurements that agree with each other: the object is elsewhere
            # (an outlier between two frames of a maneuver keeps the maneuver's first frame)
            far = self._far
            if far is not None and t > far[0]:
                fx, fy = zx - far[1], zy - far[2]
                lim = self.max_speed * (t - far[0]) + lim0
                self.n_far = self.n_far + 1 if fx * fx + fy * fy <= lim * lim else 1
            else:
                self.n_far = 1
            if self.n_far == 1:
                self._far0 = (t, zx, zy)
            self._far = (t, zx, zy)
            if self.n_far >= 3:
                f0 = self._far0
                tf = max(t - f0[0], 1e-3)
                return self._init(t, zx, zy, ((zx - f0[1]) / tf, (zy - f0[2]) / tf))
        self.outlier_rate += (1.0 - self.outlier_rate) / self.horizon
        self._set_pred(pred, cs)
        return self.estimate_fast()

    def _set_pred(self, pred: tuple[float, ...], cs: float) -> None:
        """Keep both models' predictions (no correction) and the prior model probability."""
        (self.sx, self.sy, self.spx, self.spy, self.mx, self.my, self.mvx, self.mvy,
         self.mpx, self.mpy, self.mbx, self.mby, self.mcx, self.mcy) = pred
        self.mu = cs

    # -- output ------------------------------------------------------------------------------

    def estimate_fast(self) -> Vec:
        mu = self.mu
        return (mu * self.sx + (1.0 - mu) * self.mx, mu * self.sy + (1.0 - mu) * self.my)

    def estimate(self) -> Vec | None:
        return None if self._t is None else self.estimate_fast()

    def velocity(self) -> Vec:
        if self._t is None:
            return (0.0, 0.0)
        w = 1.0 - self.mu
        return (w * self.mvx, w * self.mvy)

    def predict(self, t_s: float) -> Vec | None:
        if self._t is None:
            return None
        ex, ey = self.estimate_fast()
        vx, vy = self.velocity()
        dt = t_s - self._t
        return (ex + vx * dt, ey + vy * dt)

    def noise(self) -> float:
        """The estimated measurement noise (std, units of the measurement)."""
        return math.sqrt(self.r)


class AdaptiveIMM1D(AdaptiveIMM):
    """The same filter on x alone (orientation, through :class:`AngleFilter`; y is ignored
    and reads 0): the y arithmetic left out, since it runs for every robot in every frame."""

    __slots__ = ()

    dims = 1

    def __init__(self, params: AdaptiveParams | None = None, angle: bool = True) -> None:
        super().__init__(params, angle)

    def update(self, t_s: float, x: float, y: float) -> Vec:
        return super().update(t_s, x, 0.0)

    def revise(self, x: float, y: float) -> Vec:
        return super().revise(x, 0.0)

    def _step(self, t: float, zx: float, zy: float) -> Vec:
        t0 = self._t
        if t0 is None or t - t0 > self.gap_s:
            return self._init(t, zx, 0.0)
        dt = t - t0 if t > t0 else 0.0
        self._t = t
        r = self.r
        cs, cm, ws_s, wm_s = self._mixing(dt)
        ws_m = 1.0 - ws_s
        wm_m = 1.0 - wm_s
        q = self.q_m
        dt2 = dt * dt
        xs, ps, xm, vm, pa, pb, pc = (self.sx, self.spx, self.mx, self.mvx, self.mpx, self.mbx,
                                      self.mcx)
        x0 = ws_s * xs + ws_m * xm
        es = xs - x0
        em = xm - x0
        p0 = ws_s * (ps + es * es) + ws_m * (pa + em * em) + self.q_s * dt
        x1 = wm_s * xs + wm_m * xm
        v1 = wm_m * vm
        es = xs - x1
        em = xm - x1
        ev = vm - v1
        a1 = wm_s * (ps + es * es) + wm_m * (pa + em * em)
        b1 = wm_m * (pb + em * ev) - wm_s * es * v1
        c1 = wm_s * v1 * v1 + wm_m * (pc + ev * ev)
        xp = x1 + v1 * dt
        ap = a1 + 2.0 * dt * b1 + dt2 * c1 + q * dt2 * dt2 * 0.25
        bp = b1 + dt * c1 + q * dt2 * dt * 0.5
        cp = c1 + q * dt2
        ns = zx - x0
        nm = zx - xp
        ss = p0 + r
        sm = ap + r
        d2s = ns * ns / ss
        d2m = nm * nm / sm
        if d2s > self.gate2 and d2m > self.gate2:
            pred = (x0, 0.0, p0, 0.0, xp, 0.0, v1, 0.0, ap, 0.0, bp, 0.0, cp, 0.0)
            return self._rejected(t, dt, zx, 0.0, pred, cs)
        g = p0 / ss
        self.sx = x0 + g * ns
        self.spx = (1.0 - g) * p0
        k0 = ap / sm
        k1 = bp / sm
        self.mx = xp + k0 * nm
        self.mvx = v1 + k1 * nm
        self.mpx = (1.0 - k0) * ap
        self.mbx = (1.0 - k0) * bp
        self.mcx = cp - k1 * bp
        e = 0.5 * (d2m - d2s)
        lr = math.exp(e if e < 700.0 else 700.0) * math.sqrt(sm / ss)
        mu = cs * lr / (cs * lr + cm)
        self.mu = 1e-6 if mu < 1e-6 else (1.0 - 1e-6 if mu > 1.0 - 1e-6 else mu)
        self._accepted(t, d2m, zx, 0.0)
        return (self.mu * self.sx + (1.0 - self.mu) * self.mx, 0.0)
