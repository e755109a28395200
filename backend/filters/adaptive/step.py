"""The adaptive filter's step, written once for the 2-D filter (positions) and the 1-D one
(orientation): the noise estimates learn from the last measurement used, the still and moving
models are mixed and predicted, then corrected by the measurement (``revise``: also a second
camera's measurement of the same instant).

Where the 1-D arithmetic differs from the 2-D one (the axes' sums and averages, the Gaussians'
normalisation, no cruise model) the two stand side by side under ``if two:``; everything
else is one line for both. Each filter runs the step compiled for its dimension
(``_compiled``: ``two`` a constant, the other branches left out), so the 1-D filter runs
the x arithmetic alone (its y is 0): it runs for every robot in every frame. Plain float
arithmetic per axis (no numpy): for a 2-state filter CPython's float operations are several
times faster than small matrices.

``revise`` is the correction itself (``update`` passes it its predictions: a call costs about
a tenth of the correction) and, right after an accepted correction, does not restore the state
before the step (the correction overwrites all of it; a rejected measurement restores it
first): with eight cameras a robot is revised about five times per step.
"""

from __future__ import annotations

import ast
import inspect
import math
from collections.abc import Callable
from typing import Any, TypeVar

from ..params import AdaptiveParams
from .outliers import Outliers
from .state import Vec

#: (module globals: one lookup fewer than ``math.exp`` in the per-frame path)
_exp, _sqrt, _log = math.exp, math.sqrt, math.log

#: weight of a new normalised innovation in its running mean (the bias test)
#: (0.15, about 7 steps: round 3, from 0.1; with a lag past the gate now raising q at once, the
#: test's job is the lag building up before it, and a shorter window sees it sooner)
BIAS_A = 0.15
#: 1 / (2 x the variance of that running mean for unit white noise)
BIAS_K = (2.0 - BIAS_A) / BIAS_A / 2.0
#: below this probability the cruise model is ruled out (it rests, then restarts)
_C_FLOOR = 1e-3

_F = TypeVar("_F", bound=Callable[..., Any])


class _Step(Outliers):
    """The step as written, for both dimensions (``two``: the 2-D filter); the filters below
    run it compiled once per dimension (``_compiled``)."""

    __slots__ = ()

    def update(self, t: float, zx: float, zy: float) -> Vec:
        two = self._two
        self._prev = (self.S, self._h, self._pend, self._far, self._backup, self._book)
        if two:  # (the 1-D filter holds no velocity: see _speed_up)
            self._vheld = None
        self._pure = False
        (gap_s, q_rate, q_down, q_min, q_max, horizon, r_min, r_max, switch_sm, switch_ms, q_s,
         gate2, clutter, rho_keep, q_c, switch_c) = self._k
        if not two:
            zy = 0.0  # (the 1-D filter reads y as 0)
        cache = self._backup is None  # (after a jump, revise takes the long way)
        if not cache and self._after_jump(t, zx, zy):
            self.rejected += 1
            return self.predict(t) or (zx, zy)
        S = self.S
        if not S or t - S[0] > gap_s:
            return self._init(t, zx, zy)
        if two:
            (t0, ta, ms, r, q, age, rho, sx, sy, sp, mp, mx, my, mvx, mvy, mb, mc, ux, uy, _, _,
             cx, cy, cvx, cvy, ca, cb, cc, lam) = S
        else:
            (t0, ta, ms, r, q, age, rho, sx, sy, sp, mp, mx, my, mvx, mvy, mb, mc, ux, uy, _,
             _) = S
        # -- the noise estimates
        bk = self._book
        if bk is not None:  # learn from the last measurement used (once per instant)
            self._book = None
            bt, bx, by, d2m, nmx, nmy, w = bk
            # process noise: grows when the moving model's innovations exceed what it predicts
            # (normalised innovation squared > 1) or keep one sign (an acceleration the model
            # does not have: the running mean of the normalised innovations, squared over its
            # variance, is ~1 when unbiased); shrinks slowly otherwise: the smallest q the data
            # agree with
            ux += BIAS_A * (nmx * w - ux)
            if two:
                uy += BIAS_A * (nmy * w - uy)
                e = 0.5 * (0.5 * d2m + (ux * ux + uy * uy) * BIAS_K)
            else:
                e = 0.5 * (d2m + ux * ux * 2.0 * BIAS_K)
            e = q_rate * ((e if e < 6.0 else 6.0) - q_down)
            q *= 1.0 + e + 0.5 * e * e  # ~exp(e), |e| < 1.5
            q = q_min if q < q_min else (q_max if q > q_max else q)
            # measurement noise from the second differences of the measurements used
            # (independent of the motion model, so a wrong q does not leak into r): z_k - z_k-1
            # - c (z_k-1 - z_k-2) has variance (1 + (1 + c)^2 + c^2) r while the motion is
            # smooth (the initial value counts as one sample: a prior against a lucky first one)
            h = self._h
            if len(h) == 6:
                t1, h1x, h1y, t2, h2x, h2y = h
                if t1 > t2 and bt > t1:
                    c = (bt - t1) / (t1 - t2)
                    ex = bx - h1x - c * (h1x - h2x)
                    if two:
                        ey = by - h1y - c * (h1y - h2y)
                        e = 0.5 * (ex * ex + ey * ey) / (1.0 + (1.0 + c) * (1.0 + c) + c * c)
                    else:
                        e = ex * ex / (1.0 + (1.0 + c) * (1.0 + c) + c * c)
                    if e > 16.0 * r:
                        e = 16.0 * r
                    age += 1.0
                    if age < horizon:
                        e = r + (e - r) / (age + 1.0)
                        e = r_min if e < r_min else (r_max if e > r_max else e)
                        # the models' covariances are in units of r (while the data
                        # dominate them, as at the start, exactly): a revised r revises them
                        # too, or a track begun with r too small keeps a too small
                        # covariance, reads its own start as large innovations and raises q
                        # (round 2's slow q walk); past the horizon r moves by ~1 % a step
                        # and this is left out (it runs for every object in every frame)
                        f = e / r
                        r = e
                        sp *= f
                        mp *= f
                        mb *= f
                        mc *= f
                        if two:
                            ca *= f
                            cb *= f
                            cc *= f
                    else:
                        r += (e - r) / horizon
                        r = r_min if r < r_min else (r_max if r > r_max else r)
                self._h = (bt, bx, by, t1, h1x, h1y)
            else:
                self._h = (bt, bx, by, *h[:3])
        # -- the models: Markov switching over dt, then the mixing weights (still's share of
        # each model's start)
        dt = t - t0 if t > t0 else 0.0
        a = switch_sm * dt
        b = switch_ms * dt
        if a > 0.5:
            a = 0.5
        if b > 0.5:
            b = 0.5
        cs = (1.0 - a) * ms + b * (1.0 - ms)
        cm = 1.0 - cs
        dt2 = dt * dt
        if ms < 2e-6:
            # moving for sure (the probability at its floor): the moving model keeps its
            # state (still's share in its start is below 1e-8) and the still one restarts
            # where it is (still's own share, below 0.5 %, left out): the mixing costs nothing
            if two:
                x0x, x0y, p0 = mx, my, mp + q_s * dt
                x1x, x1y, v1x, v1y, a1, b1, c1 = mx, my, mvx, mvy, mp, mb, mc
            else:
                x0x, p0, x1x, v1x, a1, b1, c1 = mx, mp + q_s * dt, mx, mvx, mp, mb, mc
        else:
            ws_s = (1.0 - a) * ms / cs if cs > 1e-12 else 0.0
            wm_s = a * ms / cm if cm > 1e-12 else 0.0
            ws_m = 1.0 - ws_s
            wm_m = 1.0 - wm_s
            # each model's start is the mix of both (the spread of the means adds to the
            # covariance; the axes' spreads are averaged, the noise being isotropic); the
            # still model's velocity is 0, certain. In terms of the models' difference
            # d = s - m: the still model's start, then its prediction (a random walk); the
            # moving model's start, then constant velocity
            dx = sx - mx
            x0x = mx + ws_s * dx
            x1x = mx + wm_s * dx
            v1x = wm_m * mvx
            if two:
                dy = sy - my
                d2 = dx * dx + dy * dy
                x0y = my + ws_s * dy
                p0 = ws_s * sp + ws_m * mp + 0.5 * ws_s * ws_m * d2 + q_s * dt
                k = 0.5 * wm_s * wm_m
                x1y = my + wm_s * dy
                v1y = wm_m * mvy
                a1 = wm_s * sp + wm_m * mp + k * d2
                b1 = wm_m * mb - k * (dx * mvx + dy * mvy)
                c1 = wm_m * mc + k * (mvx * mvx + mvy * mvy)
            else:
                p0 = ws_s * sp + ws_m * mp + ws_s * ws_m * dx * dx + q_s * dt
                k = wm_s * wm_m
                a1 = wm_s * sp + wm_m * mp + k * dx * dx
                b1 = wm_m * mb - k * dx * mvx
                c1 = wm_m * mc + k * mvx * mvx
        ap = a1 + 2.0 * dt * b1 + dt2 * c1 + q * dt2 * dt2 * 0.25
        bp = b1 + dt * c1 + q * dt2 * dt * 0.5
        cp = c1 + q * dt2
        # what the correction needs that does not depend on the measurement (once per
        # instant: a second camera's revise only redoes the rest): inverse innovation
        # variances, both gates, gains, corrected covariances, the prior odds, the next
        # outlier rate, the weight of a normalised innovation
        ss = p0 + r
        sm = ap + r
        iss = 1.0 / ss
        ism = 1.0 / sm
        g2 = gate2
        # gate: inside the gate of a model that is not all but ruled out (a model of
        # negligible probability can be wide enough to take anything)
        gs2 = g2 if cs >= 0.05 else -1.0
        gm2 = g2 if cm >= 0.05 else -1.0
        k0 = ap * ism
        k1 = bp * ism
        g = p0 * iss
        if two:
            vchk = 0.0
            if rho > 1e-3 and gm2 > 0.0:
                # outliers seen: a measurement is the moving model's only where it is likelier
                # from it than a false detection ((1 - rho) N(d; S) > rho / area) and where it
                # leaves the velocity possible; right after a jump the prediction is wide, and
                # a wide gate would catch the next false detection and run off with it (2-D only)
                e = (1.0 - rho) / (rho * clutter * sm)
                if e < 1e8:
                    e = 2.0 * _log(e) if e > 1.0 else 0.0
                    if e < gm2:
                        gm2 = e
                vchk = 1.0
            # the cruise model (2-D only): constant velocity with a small fixed q, beside the
            # moving one (not mixed with it: restarted from it, see revise); lam < 0: it rests
            # (ruled out by a maneuver: the moving model alone) until the time -lam
            if lam >= 0.0 or t >= -lam:
                if lam < 0.0:  # it wakes where the moving model is
                    cx, cy, cvx, cvy, ca, cb, cc, lam = mx, my, mvx, mvy, mp, mb, mc, 1e-3
                qd = q_c * dt2
                cap = ca + 2.0 * dt * cb + dt2 * cc + qd * dt2 * 0.25
                cbp = cb + dt * cc + qd * dt * 0.5
                ccp = cc + qd
                isc = 1.0 / (cap + r)
                kc0 = cap * isc
                kc1 = cbp * isc
                e = switch_c * dt
                lp = lam + e * (1.0 - 2.0 * lam) if e < 0.5 else 0.5
                # its prediction, gains, corrected covariance, the prior odds moving / cruise x
                # the normalisations' ratio
                cpri: tuple[float, ...] | None = (
                    cx + cvx * dt, cy + cvy * dt, cvx, cvy, cap, cbp, ccp, isc, kc0, kc1,
                    (1.0 - kc0) * cap, (1.0 - kc0) * cbp, ccp - kc1 * cbp, lp,
                    (1.0 - lp) * (cap + r) * ism / lp)
            else:
                cpri = None
            pri: tuple[Any, ...] = (
                t, ta, dt, cs, cm, r, q, age, rho, ux, uy, x0x, x0y, p0,
                x1x + v1x * dt, x1y + v1y * dt, v1x, v1y, ap, bp, cp,
                iss, ism, gs2, gm2, vchk, g, (1.0 - g) * p0, k0, k1, (1.0 - k0) * ap,
                (1.0 - k0) * bp, cp - k1 * bp,
                # prior odds moving / still x the ratio of the Gaussians' normalisations (2-D)
                cm * ss / (cs * sm) if cs > 1e-300 else 1e300, rho * rho_keep,
                _sqrt(ism), cpri, lam)
        else:
            pri = (
                t, ta, dt, cs, cm, r, q, age, rho, ux, x0x, p0, x1x + v1x * dt, v1x, ap, bp,
                cp, iss, ism, gs2, gm2, g, (1.0 - g) * p0, k0, k1, (1.0 - k0) * ap,
                (1.0 - k0) * bp, cp - k1 * bp,
                # prior odds moving / still x the ratio of the Gaussians' normalisations (1-D)
                cm * _sqrt(ss * ism) / cs if cs > 1e-300 else 1e300, rho * rho_keep,
                _sqrt(ism))
        self._pri = pri if cache else None
        self._pri_h = self._h
        return self.revise(zx, zy, pri)

    def revise(self, zx: float, zy: float, pri: tuple[Any, ...] | None = None) -> Vec:
        """A second camera's measurement at the last step's instant instead of the last one:
        the measurement against the step's predictions again. ``pri``: update's own
        predictions (the step's second half: one function for both, since a call costs about
        a tenth of the correction, and this runs for every object each camera sees)."""
        if pri is None:
            pri = self._pri
            if pri is None or pri[0] != self.S[0]:  # no predictions of this step
                return self._redo(zx, zy)
            if not self._pure:
                self._restore()
            # (else the correction overwrites all the step changed after its predictions, and
            # restores the state before the step itself if it rejects the measurement: a
            # second camera's revise, the common case, costs the correction alone)
        two = self._two
        if two:
            (t, ta, dt, cs, cm, r, q, age, rho, ux, uy, x0x, x0y, p0, xpx, xpy, v1x, v1y, ap,
             bp, cp, iss, ism, gs2, gm2, vchk, g, sp, k0, k1, ap1, bp1, cp1, cr, rho1, w, cpri,
             lam) = pri
            nsx = zx - x0x
            nsy = zy - x0y
            nmx = zx - xpx
            nmy = zy - xpy
            d2s = (nsx * nsx + nsy * nsy) * iss
            d2m = (nmx * nmx + nmy * nmy) * ism
            vx = v1x + k1 * nmx
            vy = v1y + k1 * nmy
            if d2s > gs2 and (d2m > gm2 or (vchk and vx * vx + vy * vy > self.max_speed2)):
                if self._pure:  # a revise (see there)
                    self._restore()
                if cpri is None:
                    return self._rejected(t, dt, zx, zy, [
                        t, ta, cs, r, q, age, rho, x0x, x0y, p0, ap, xpx, xpy, v1x, v1y, bp, cp,
                        ux, uy, cs * x0x + cm * xpx, cs * x0y + cm * xpy,
                        xpx, xpy, v1x, v1y, ap, bp, cp, lam])
                cpx, cpy, cvx, cvy, cap, cbp, ccp, _, _, _, _, _, _, lp, _ = cpri
                mox = lp * cpx + (1.0 - lp) * xpx
                moy = lp * cpy + (1.0 - lp) * xpy
                return self._rejected(t, dt, zx, zy, [
                    t, ta, cs, r, q, age, rho, x0x, x0y, p0, ap, xpx, xpy, v1x, v1y, bp, cp,
                    ux, uy, cs * x0x + cm * mox, cs * x0y + cm * moy,
                    cpx, cpy, cvx, cvy, cap, cbp, ccp, lp])
        else:
            (t, ta, dt, cs, cm, r, q, age, rho, ux, x0x, p0, xpx, v1x, ap, bp, cp, iss, ism,
             gs2, gm2, g, sp, k0, k1, ap1, bp1, cp1, cr, rho1, w) = pri
            nsx = zx - x0x
            nmx = zx - xpx
            d2s = nsx * nsx * iss
            d2m = nmx * nmx * ism
            if d2s > gs2 and d2m > gm2:
                if self._pure:
                    self._restore()
                return self._rejected(t, dt, zx, 0.0, [
                    t, ta, cs, r, q, age, rho, x0x, 0.0, p0, ap, xpx, 0.0, v1x, 0.0, bp, cp, ux,
                    0.0, cs * x0x + cm * xpx, 0.0])
        # -- model probabilities: the Gaussian likelihood ratio still / moving
        e = 0.5 * (d2s - d2m)
        mu = 1.0 / (1.0 + cr * _exp(e if e < 700.0 else 700.0))
        mu = 1e-6 if mu < 1e-6 else (1.0 - 1e-6 if mu > 1.0 - 1e-6 else mu)
        # the noise estimates learn from this measurement at the next step (once per instant,
        # however often a second camera revises it); the 1-D filter reads y as 0
        if two:
            self._book = (t, zx, zy, d2m, nmx, nmy, w)
        else:
            self._book = (t, zx, 0.0, d2m, nmx, 0.0, w)
        if self._pend is not None or self._far is not None or self._backup is not None:
            self._pend = self._far = self._backup = None
        # -- corrections
        sx = x0x + g * nsx
        mx = xpx + k0 * nmx
        if two:
            sy = x0y + g * nsy
            my = xpy + k0 * nmy
            # cruise / moving: the likelihood ratio; a cruise model all but ruled out (a maneuver)
            # rests, then restarts from the moving one (what an IMM's mixing would do, for less)
            if cpri is not None:
                cpx, cpy, cvx, cvy, _, _, _, isc, kc0, kc1, ca1, cb1, cc1, lp, crc = cpri
                ncx = zx - cpx
                ncy = zy - cpy
                e = 0.5 * ((ncx * ncx + ncy * ncy) * isc - d2m)
                lam = 1.0 / (1.0 + crc * _exp(e if e < 700.0 else 700.0))
                if lam > _C_FLOOR:
                    if lam > 0.999:
                        lam = 0.999
                    cx = cpx + kc0 * ncx
                    cy = cpy + kc0 * ncy
                    w = 1.0 - mu
                    ex = mu * sx + w * (lam * cx + (1.0 - lam) * mx)
                    ey = mu * sy + w * (lam * cy + (1.0 - lam) * my)
                    self.S = [t, t, mu, r, q, age, rho1, sx, sy, sp, ap1, mx, my, vx, vy, bp1, cp1,
                              ux, uy, ex, ey, cx, cy, cvx + kc1 * ncx, cvy + kc1 * ncy, ca1, cb1,
                              cc1, lam]
                    self._pure = True
                    return (ex, ey)
                lam = -(t + self.c_rest)
            w = 1.0 - mu
            ex = mu * sx + w * mx
            ey = mu * sy + w * my
            self.S = [t, t, mu, r, q, age, rho1, sx, sy, sp, ap1, mx, my, vx, vy, bp1, cp1, ux, uy,
                      ex, ey, mx, my, vx, vy, ap1, bp1, cp1, lam]
            self._pure = True
            return (ex, ey)
        else:
            ex = mu * sx + (1.0 - mu) * mx
            self.S = [t, t, mu, r, q, age, rho1, sx, 0.0, sp, ap1, mx, 0.0, v1x + k1 * nmx, 0.0,
                      bp1, cp1, ux, 0.0, ex, 0.0]
            self._pure = True
            return (ex, 0.0)


class _Dims(ast.NodeTransformer):
    """``two`` made a constant: of ``if two:`` and ``if not two:`` only the branch taken is
    left, ``two = ...`` goes, and any other read of ``two`` is refused."""

    def __init__(self, two: bool) -> None:
        self.two = two

    def _test(self, node: ast.expr) -> bool | None:
        if isinstance(node, ast.Name) and node.id == "two":
            return self.two
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
            v = self._test(node.operand)
            return None if v is None else not v
        return None

    def visit_If(self, node: ast.If) -> Any:
        v = self._test(node.test)
        if v is None:
            return self.generic_visit(node)
        out: list[ast.stmt] = []
        for stmt in node.body if v else node.orelse:
            done = self.visit(stmt)
            out += done if isinstance(done, list) else [] if done is None else [done]
        return out  # (nothing left: the statement goes, no ``pass`` to run)

    def visit_Assign(self, node: ast.Assign) -> Any:
        if any(isinstance(t, ast.Name) and t.id == "two" for t in node.targets):
            return None
        return self.generic_visit(node)

    def visit_Name(self, node: ast.Name) -> Any:
        if node.id == "two":
            raise ValueError(f"line {node.lineno}: `two` read outside `if two:` / `if not two:`")
        return node


def _compiled(f: _F, two: bool, qualname: str) -> _F:
    """``f`` (a method of ``_Step``) compiled with ``two`` a constant, so the compiler leaves
    out the other dimension's branches: each filter's step costs what a step written for its
    dimension alone costs. Measured on the world model's pattern (a robot's position, then
    its orientation): the branches cost the 1-D step 3.7 % and the 2-D one 0.6 % more
    instructions, and one code object for both filters made CPython's attribute caches
    (one type at a time) miss, +12 % per robot. The source and its lines are ``f``'s
    (tracebacks, coverage and breakpoints point at it)."""
    lines, first = inspect.getsourcelines(f)
    # parsed as the body of an ``if``: the method keeps its indentation and columns
    tree = ast.parse("if 1:\n" + "".join(lines))
    ast.increment_lineno(tree, first - 2)
    top = tree.body[0]
    assert isinstance(top, ast.If) and isinstance(top.body[0], ast.FunctionDef)
    module = ast.Module(body=[_Dims(two).visit(top.body[0])], type_ignores=[])
    # (compile inherits this module's future import: the annotations stay unevaluated)
    code = compile(ast.fix_missing_locations(module), inspect.getsourcefile(f) or "<step>",
                   "exec")
    ns: dict[str, Any] = {}
    exec(code, f.__globals__, ns)
    g = ns[f.__name__]
    g.__qualname__ = qualname
    return g  # type: ignore[no-any-return]


class AdaptiveIMM(_Step):
    """Still/moving IMM with estimated noise and robust gating (see the package doc), 2-D."""

    __slots__ = ()

    update = _compiled(_Step.update, True, "AdaptiveIMM.update")
    revise = _compiled(_Step.revise, True, "AdaptiveIMM.revise")


class AdaptiveIMM1D(AdaptiveIMM):
    """The same filter on x alone (orientation, through :class:`AngleFilter`; y is ignored
    and reads 0): the y arithmetic left out, since it runs for every robot in every frame."""

    __slots__ = ()

    dims = 1

    update = _compiled(_Step.update, False, "AdaptiveIMM1D.update")
    revise = _compiled(_Step.revise, False, "AdaptiveIMM1D.revise")

    def __init__(self, params: AdaptiveParams | None = None, angle: bool = True) -> None:
        super().__init__(params, angle)

    def _init(self, t: float, x: float, y: float, v: Vec = (0.0, 0.0), mu: float = 0.5,
              pvv: float | None = None) -> Vec:
        # the still/moving pair alone (no cruise model): the state without its 2-D tail
        out = super()._init(t, x, y, v, mu, pvv)
        del self.S[21:]
        return out

    def velocity(self) -> Vec:
        bk = self._backup
        S: list[float] = self.S if bk is None else bk[0]  # type: ignore[assignment]
        if not S:
            return (0.0, 0.0)
        return ((1.0 - S[2]) * S[13], 0.0)

    def predict(self, t_s: float) -> Vec | None:
        S = self.S
        if not S:
            return None
        return (S[19] + (1.0 - S[2]) * (t_s - S[0]) * S[13], 0.0)
