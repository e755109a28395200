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

from .params import AdaptiveParams, FilterKind

Vec = tuple[float, float]

import os
ETA=float(os.environ.get("ETA","0.2"))
DELTA=float(os.environ.get("DELTA","0.2"))
Q0=float(os.environ.get("Q0","300"))


class AdaptiveIMM:
    """Still/moving IMM with estimated measurement noise and robust gating (see module doc).

    ``dims=1`` filters x only (orientation through :class:`AngleFilter`, y is ignored)."""

    __slots__ = (
        "_age", "_backup", "_hist", "_far", "_far0", "_pend", "_prev", "_t", "_ta",
        "dims", "gap_s", "gate2", "kind", "max_speed", "mu", "n_far", "outlier_rate", "q_m",
        "q_max", "q_min", "q_s", "r", "r_max", "r_min", "rejected", "rho_accept", "s", "switch_ms", "switch_sm",
        "vx", "horizon",
    )

    def __init__(self, params: AdaptiveParams | None = None, angle: bool = False,
                 dims: int = 2) -> None:
        p = params or AdaptiveParams()
        self.kind: FilterKind = "adaptive"
        self.dims = dims
        if angle:
            r0, rmin, rmax = p.angle_init_noise_rad, p.angle_min_noise_rad, p.angle_max_noise_rad
            self.q_m = p.angle_accel_noise_rad_s2 ** 2
            self.q_min, self.q_max = 1e-4, 1e4 ** 2
            self.q_s = p.angle_still_drift_rad_s ** 2
            self.max_speed = p.angle_max_rate_rad_s
        else:
            r0, rmin, rmax = p.init_noise_mm, p.min_noise_mm, p.max_noise_mm
            self.q_m = Q0 ** 2
            self.q_min, self.q_max = 1.0, 1e5 ** 2
            self.q_s = p.still_drift_mm_s ** 2
            self.max_speed = p.max_speed_mm_s
        self.r = r0 * r0
        self.r_min, self.r_max = rmin * rmin, rmax * rmax
        self.gate2 = p.gate_sigma ** 2
        self.gap_s = p.gap_s
        self.horizon = p.noise_horizon
        self.switch_sm = p.still_to_moving_per_s
        self.switch_ms = p.moving_to_still_per_s
        self.rho_accept = 0.02  # outlier rate below which a reachable jump is a maneuver at once
        self.rejected = 0
        self.outlier_rate = 0.0
        self.n_far = 0
        self._t: float | None = None
        self._ta = 0.0  # time of the last measurement used
        self._age = 0.0  # accepted measurements so far (the noise average's count)
        self.mu = 0.5  # probability of "still"
        # still model per axis [x, P]; moving model per axis [x, v, Ppp, Ppv, Pvv]
        self.s: list[float] = []
        self.vx: list[float] = []
        self._pend: tuple[float, float, float] | None = None  # last reachable rejected (t, x, y)
        self._far: tuple[float, float, float] | None = None  # last unreachable one
        self._far0 = (0.0, 0.0, 0.0)  # the first of the run of unreachable ones
        self._backup: tuple[object, ...] | None = None  # the track before a jump
        self._hist: list[float] = []  # the last two measurements used: t, x, y, t, x, y
        self._prev: tuple[object, ...] | None = None  # state before the last update (revise)

    # -- state -------------------------------------------------------------------------------

    @property
    def t_last(self) -> float | None:
        return self._t

    def reset(self) -> None:
        self._t = None
        self._prev = None
        self._pend = None
        self.s, self.vx = [], []
        self._age = 0.0
        self.n_far = 0

    def _save(self) -> tuple[object, ...]:
        return (self._t, self.mu, list(self.s), list(self.vx), self.r, self._age,
                self.outlier_rate, self._pend, self.n_far, self.rejected, self._far, self.q_m,
                self._ta, self._hist)

    def _load(self, st: tuple[object, ...]) -> None:
        (t, mu, s, vx, r, age, rho, pend, nfar, rej, far, qm, ta, hist) = st
        self._hist = hist  # type: ignore[assignment]
        self._ta = ta  # type: ignore[assignment]
        self._far = far  # type: ignore[assignment]
        self.q_m = qm  # type: ignore[assignment]
        self._t = t  # type: ignore[assignment]
        self.mu = mu  # type: ignore[assignment]
        self.s = list(s)  # type: ignore[call-overload]
        self.vx = list(vx)  # type: ignore[call-overload]
        self.r = r  # type: ignore[assignment]
        self._age = age  # type: ignore[assignment]
        self.outlier_rate = rho  # type: ignore[assignment]
        self._pend = pend  # type: ignore[assignment]
        self.n_far = nfar  # type: ignore[assignment]
        self.rejected = rej  # type: ignore[assignment]

    def _init(self, t: float, x: float, y: float, v: Vec = (0.0, 0.0), mu: float = 0.5,
              pvv: float | None = None) -> Vec:
        r = self.r
        pv = pvv if pvv is not None else self.max_speed ** 2 / 4
        self.s = [x, r, y, r]
        self.vx = [x, v[0], r, 0.0, pv, y, v[1], r, 0.0, pv]
        self.mu = mu
        self._t = self._ta = t
        self._hist = [t, x, y]
        self._pend = self._far = self._backup = None
        self.n_far = 0
        return (x, y)

    # -- the step ----------------------------------------------------------------------------

    def update(self, t_s: float, x: float, y: float) -> Vec:
        self._prev = self._save()
        return self._step(t_s, x, y)

    def revise(self, x: float, y: float) -> Vec:
        if self._prev is None or self._t is None:
            return self.update(0.0 if self._t is None else self._t, x, y)
        t = self._t
        self._load(self._prev)
        if self._t is None:
            return self.update(t, x, y)
        return self._step(t, x, y)

    def _step(self, t: float, zx: float, zy: float) -> Vec:
        t0 = self._t
        if t0 is None or not self.s or t - t0 > self.gap_s:
            return self._init(t, zx, zy)
        dt = t - t0
        if dt < 0.0:
            dt = 0.0
        self._t = t
        r = self.r
        two = self.dims == 2
        # Markov switching over dt, and the mixing weights
        ms = self.mu
        mm = 1.0 - ms
        a = min(0.5, self.switch_sm * dt)
        b = min(0.5, self.switch_ms * dt)
        cs = (1.0 - a) * ms + b * mm
        cm = 1.0 - cs
        ws_s = (1.0 - a) * ms / cs if cs > 1e-12 else 0.0
        ws_m = 1.0 - ws_s
        wm_s = a * ms / cm if cm > 1e-12 else 0.0
        wm_m = 1.0 - wm_s
        qs = self.q_s * dt
        q = self.q_m
        dt2 = dt * dt
        q11, q12, q22 = q * dt2 * dt2 / 4.0, q * dt2 * dt / 2.0, q * dt2
        s = self.s
        m = self.vx
        # per axis: mix, predict (still: xs, Ps; moving: xm, vm, A, B, C), innovation terms
        pri: list[float] = []
        d2s = d2m = 0.0
        lds = ldm = 0.0
        for ax in (0, 1) if two else (0,):
            xs, ps = s[2 * ax], s[2 * ax + 1]
            k = 5 * ax
            xm, vm, pa, pb, pc = m[k], m[k + 1], m[k + 2], m[k + 3], m[k + 4]
            # mixed start of "still"
            x0 = ws_s * xs + ws_m * xm
            es, em = xs - x0, xm - x0
            p0 = ws_s * (ps + es * es) + ws_m * (pa + em * em) + qs
            # mixed start of "moving" (still contributes v = 0 with no uncertainty)
            x1 = wm_s * xs + wm_m * xm
            v1 = wm_m * vm
            es, em = xs - x1, xm - x1
            ev = vm - v1
            a1 = wm_s * (ps + es * es) + wm_m * (pa + em * em)
            b1 = wm_s * (es * -v1) + wm_m * (pb + em * ev)
            c1 = wm_s * (v1 * v1) + wm_m * (pc + ev * ev)
            # constant-velocity prediction
            xp = x1 + v1 * dt
            ap = a1 + 2.0 * dt * b1 + dt2 * c1 + q11
            bp = b1 + dt * c1 + q12
            cp = c1 + q22
            z = zx if ax == 0 else zy
            ns, nm = z - x0, z - xp
            ss, sm = p0 + r, ap + r
            d2s += ns * ns / ss
            d2m += nm * nm / sm
            lds += math.log(ss)
            ldm += math.log(sm)
            pri += (x0, p0, xp, v1, ap, bp, cp, ns, nm, ss, sm)
        if min(d2s, d2m) > self.gate2:
            return self._rejected(t, dt, zx, zy, pri, cs)
        # both models' corrections
        out_s: list[float] = []
        out_m: list[float] = []
        for ax in (0, 1) if two else (0,):
            x0, p0, xp, v1, ap, bp, cp, ns, nm, ss, sm = pri[11 * ax:11 * ax + 11]
            g = p0 / ss
            out_s += (x0 + g * ns, (1.0 - g) * p0)
            k0, k1 = ap / sm, bp / sm
            out_m += (xp + k0 * nm, v1 + k1 * nm, (1.0 - k0) * ap, (1.0 - k0) * bp,
                      cp - k1 * bp)
        # model likelihoods (log, Gaussian) and the new probabilities
        ls = -0.5 * (d2s + lds)
        lm = -0.5 * (d2m + ldm)
        top = max(ls, lm)
        ps_ = cs * math.exp(ls - top)
        pm_ = cm * math.exp(lm - top)
        mu = ps_ / (ps_ + pm_)
        self.mu = min(1.0 - 1e-6, max(1e-6, mu))
        self.s = out_s
        self.vx = out_m
        self._pend = self._far = self._backup = None
        self._ta = t
        self.n_far = 0
        self.outlier_rate -= self.outlier_rate / self.horizon
        # process noise: grow when the moving model's innovations are larger than it predicts,
        # shrink slowly otherwise (the smallest q the data agree with)
        nis = d2m / (2 if two else 1)
        self.q_m = min(self.q_max, max(self.q_min, self.q_m * math.exp(
            ETA * (min(nis, 20.0) - 1.0 - DELTA))))
        # measurement noise from the second differences of the measurements used (independent
        # of the motion model, so a wrong q does not leak into r): z_k - z_k-1 - rho (z_k-1 -
        # z_k-2) has variance (1 + (1 + rho)^2 + rho^2) r when the motion is smooth
        r_new = r
        h = self._hist
        if len(h) == 6:
            t1, x1, y1, t2, x2, y2 = h
            if t1 > t2 and t > t1:
                rho = (t - t1) / (t1 - t2)
                ex = zx - x1 - rho * (x1 - x2)
                e2 = ex * ex
                if two:
                    ey = zy - y1 - rho * (y1 - y2)
                    e2 = 0.5 * (e2 + ey * ey)
                sample = min(e2 / (1.0 + (1.0 + rho) ** 2 + rho * rho), 16.0 * r)
                self._age += 1.0
                r_new = r + (sample - r) / min(self._age + 1.0, self.horizon)
            self._hist = [t, zx, zy, t1, x1, y1]
        elif len(h) == 3:
            self._hist = [t, zx, zy, *h]
        else:
            self._hist = [t, zx, zy]
        self.r = min(self.r_max, max(self.r_min, r_new))
        return self.estimate_fast()

    def _rejected(self, t: float, dt: float, zx: float, zy: float, pri: list[float],
                  cs: float) -> Vec:
        """A measurement outside both models' gates: an outlier, a maneuver or a new place."""
        self.rejected += 1
        two = self.dims == 2
        bk = self._backup
        if bk is not None:
            # the last step re-initialised on a jump; if this measurement fits the track from
            # before that jump, the jump was an outlier after all: go back to that track
            self._backup = None
            cur = self._save()
            n_rej = self.rejected
            self._load(bk)
            self.rejected = n_rej
            out = self._step(t, zx, zy)
            if self.rejected == n_rej:
                return out
            self._load(cur)
            self.rejected = n_rej
        ex = self.estimate_fast()
        dx, dy = zx - ex[0], (zy - ex[1]) if two else 0.0
        lim0 = math.sqrt(self.gate2 * self.r)
        reach = self.max_speed * (t - self._ta) + lim0
        pend = self._pend
        confirmed = False
        v = (0.0, 0.0)
        if pend is not None and t > pend[0]:  # does it continue the last reachable jump?
            px, py = zx - pend[1], (zy - pend[2]) if two else 0.0
            tp = t - pend[0]
            lim = self.max_speed * tp + lim0
            # a maneuver continues away from where the object was, in about the same direction
            ox, oy = pend[1] - ex[0], (pend[2] - ex[1]) if two else 0.0
            along = px * ox + py * oy
            if (px * px + py * py <= lim * lim and along > 0.0
                    and along * along >= 0.5 * (px * px + py * py) * (ox * ox + oy * oy)):
                confirmed = True
                v = (px / tp, py / tp)
        reachable = confirmed or dx * dx + dy * dy <= reach * reach
        if reachable:
            if not confirmed and dt > 0:
                v = (dx / dt, dy / dt)
            if confirmed or self.outlier_rate < self.rho_accept:
                dv2 = v[0] * v[0] + v[1] * v[1]
                bk = self._save_pred(pri, cs)
                self._init(t, zx, zy, v, mu=1e-3, pvv=dv2 + self.r / max(dt, 1e-3) ** 2)
                self._backup = bk
                return (zx, zy)
            self._pend = (t, zx, zy)
        else:
            # (an outlier between two frames of a maneuver leaves the maneuver's first frame)
            # a run of far measurements that agree with each other: the object is elsewhere
            far = self._far
            if far is not None and t > far[0]:
                fx, fy = zx - far[1], (zy - far[2]) if two else 0.0
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
        # keep the predictions (no correction) and the prior model probabilities
        self._load(self._save_pred(pri, cs))
        return self.estimate_fast()

    def _save_pred(self, pri: list[float], cs: float) -> tuple[object, ...]:
        """The state with both models' predictions and the prior model probabilities."""
        s: list[float] = []
        m: list[float] = []
        for ax in (0, 1) if self.dims == 2 else (0,):
            x0, p0, xp, v1, ap, bp, cp = pri[11 * ax:11 * ax + 7]
            s += (x0, p0)
            m += (xp, v1, ap, bp, cp)
        st = list(self._save())
        st[1], st[2], st[3] = cs, s, m
        return tuple(st)

    # -- output ------------------------------------------------------------------------------

    def estimate_fast(self) -> Vec:
        s, m, mu = self.s, self.vx, self.mu
        x = mu * s[0] + (1.0 - mu) * m[0]
        if self.dims == 2:
            return (x, mu * s[2] + (1.0 - mu) * m[5])
        return (x, 0.0)

    def estimate(self) -> Vec | None:
        if not self.s:
            return None
        return self.estimate_fast()

    def velocity(self) -> Vec:
        if not self.s:
            return (0.0, 0.0)
        w = 1.0 - self.mu
        m = self.vx
        return (w * m[1], w * m[6] if self.dims == 2 else 0.0)

    def predict(self, t_s: float) -> Vec | None:
        if not self.s or self._t is None:
            return None
        e = self.estimate_fast()
        vx, vy = self.velocity()
        dt = t_s - self._t
        return (e[0] + vx * dt, e[1] + vy * dt)

    def noise(self) -> float:
        """The estimated measurement noise (std, units of the measurement)."""
        return math.sqrt(self.r)
