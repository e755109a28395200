"""Plays: who takes which role, and the referee-driven behaviour every play obeys.

A play lists *slots* in priority order (goalkeeper, attacker, defender, supporter, ...), each
with a spot used for the assignment cost and a function that makes the robot's ``Intent``.
``StableAssigner`` gives each robot a slot (minimum total distance, or bottleneck, with
hysteresis so roles do not flicker). The referee's situation changes the slots:

=================  ==========================================================================
HALT               nobody moves (control zeroes every robot too)
STOP               no kicks, <= 1.5 m/s, every target and path >= stop distance from the ball;
                   the attacker becomes a blocker between ball and our goal; 0.2 m from the
                   opponents' defence area (``core.STOPPED_DEFENSE_MARGIN_MM``)
kickoff            everyone in our half outside the centre circle; our kicker behind the ball,
                   it kicks after NORMAL_START
penalty            ours: kicker behind the ball, the rest 1 m behind it; theirs: keeper on
                   the goal line, the rest 1 m behind the ball
free kick          ours: the kicker shoots (direct, open goal) or passes; theirs: a blocker
                   and every robot >= stop distance from the ball
ball placement     ours: the placer carries the ball to the mark with the dribbler (into a
                   defence area too, to fetch the ball); theirs:
                   every robot >= stop distance from the ball-to-mark segment
timeout            robots parked along our touch line
side switch        the referee's side flag flips our frame (see ``model.Frame``)
=================  ==========================================================================
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from domain.angles import wrap_angle
from domain.field import Field

from .assignment import StableAssigner
from .formations import FormationConfig, formation
from .model import ROBOT_RADIUS_MM, Ball, Bot, Intent
from .roles import (
    CONTACT_MM,
    attacker,
    best_shot,
    clamp_to_field,
    defender_points,
    goalkeeper,
    kick_ball,
    push_out_of_capsule,
    push_out_of_circle,
    supporter_points,
    unit,
)
from .situation import Situation

R = ROBOT_RADIUS_MM

PLAY_INFO: dict[str, tuple[str, str]] = {
    "match": ("Match", "Full game: goalkeeper, attacker, defenders and supporters; obeys "
                       "every referee command"),
    "defend": ("Defend only", "Goalkeeper and a wall of defenders between ball and goal"),
    "attack-drill": ("Attack drill", "Go behind the ball, pick the widest open angle, score"),
    "formation": ("Formation (classroom)", "Robots move between formations on our half; "
                                           "keeps clear of the ball when the referee says so"),
    "simple": ("Simple opponent", "Keeper mirrors the ball, one chaser kicks at the goal "
                                  "centre, the rest stand; obeys the referee"),
    "idle": ("Idle", "No autonomous moves: robots move only on operator targets"),
}


@dataclass(frozen=True, slots=True)
class Tuning:
    """The strategy parameters the plays use (from ``StrategyParams``)."""

    kick_speed_mps: float = 5.5
    pass_speed_mps: float = 3.0
    stop_distance_mm: float = 650.0
    defense_margin_mm: float = 120.0
    robot_margin_mm: float = 60.0
    placement_speed_mps: float = 0.8
    keeper_min_speed_mmps: float = 300.0
    formation_period_s: float = 5.0


@dataclass(frozen=True, slots=True)
class StrategyInput:
    t: float  # s, a monotonic clock (formations change with it)
    ours: Sequence[Bot]  # our frame
    theirs: Sequence[Bot]
    ball: Ball | None
    fs: Field
    situation: Situation  # designated position already in our frame
    keeper_id: int | None = None  # from the referee
    keeper_point: tuple[float, float] | None = None  # e.g. from the compute engine
    play: str = "match"
    tuning: Tuning = Tuning()
    max_bots: int | None = None  # robots allowed on the field (the referee; cards lower it)


Make = Callable[[Bot], Intent]


@dataclass(frozen=True, slots=True)
class Slot:
    name: str  # unique: "goalkeeper", "defender-2", ...
    role: str  # shown on the field: "goalkeeper", "defender", ...
    xy: tuple[float, float]  # spot for the assignment cost
    make: Make


def _hold(role: str, xy: tuple[float, float], face: float | None = None,
          **kw: float | bool | None) -> Make:
    def make(bot: Bot) -> Intent:
        return Intent(role, xy[0], xy[1], face, **kw)  # type: ignore[arg-type]
    return make


class Strategy:
    """Stateful across ticks only where the game needs memory: the role assignment (for
    stability) and who took the last set piece (no double touch)."""

    def __init__(self, assignment: str = "sum", hysteresis_mm: float = 400.0) -> None:
        self.assigner = StableAssigner(mode=assignment,  # type: ignore[arg-type]
                                       hysteresis_mm=hysteresis_mm)
        self.roles: dict[int, str] = {}
        self._set_piece_kicker: int | None = None
        self._kicker_banned_until = -1.0
        self._last_kind = ""
        self._last_play = ""
        self.leaving: set[int] = set()  # robots sent off the field (more than allowed)

    def configure(self, assignment: str, hysteresis_mm: float) -> None:
        self.assigner.mode = assignment  # type: ignore[assignment]
        self.assigner.hysteresis_mm = hysteresis_mm

    def decide(self, inp: StrategyInput) -> dict[int, Intent]:
        """Intents for our visible robots (our frame)."""
        if inp.play != self._last_play:
            self.assigner.reset()
            self._last_play = inp.play
        if inp.play == "idle" or not inp.ours:
            self.roles = {}
            self.leaving = set()
            return {}
        everyone = inp  # with the robots leaving the field, for the rules every robot obeys
        leaving = self._choose_leaving(inp)
        if leaving:
            inp = replace(inp, ours=[b for b in inp.ours if b.id not in leaving])
        sit = inp.situation
        # double touch: the robot that took a kickoff or free kick keeps off the ball a while
        if self._last_kind in ("kickoff", "free-kick") and sit.kind == "running":
            self._kicker_banned_until = inp.t + 1.5
        self._last_kind = sit.kind
        slots = self._slots(inp)
        bots = {b.id: b for b in inp.ours}
        ids = sorted(bots)
        xy = np.array([bots[i].xy for i in ids], dtype=np.float64)
        sxy = np.array([s.xy for s in slots], dtype=np.float64).reshape(-1, 2)
        extra = None  # no extra cost: the same as zeros (a distance + 0.0 is itself)
        if self._set_piece_kicker in bots and inp.t < self._kicker_banned_until:
            extra = np.zeros((len(ids), len(slots)))
            r = ids.index(self._set_piece_kicker)
            for k, s in enumerate(slots):
                if s.role == "attacker":
                    extra[r, k] = 1e6
        fixed = {}
        if inp.keeper_id in bots and any(s.name == "goalkeeper" for s in slots):
            fixed[inp.keeper_id] = "goalkeeper"
        chosen = self.assigner.assign(ids, xy, [s.name for s in slots], sxy,
                                      extra_cost=extra, fixed=fixed)
        by_name = {s.name: s for s in slots}
        out: dict[int, Intent] = {}
        for rid, name in chosen.items():
            slot = by_name[name]
            it = slot.make(bots[rid])
            if slot.role == "kicker":
                self._set_piece_kicker = rid
            out[rid] = it
        for rid in ids:  # robots without a slot (more robots than slots) hold still
            if rid not in out:
                b = bots[rid]
                out[rid] = Intent("waiting", b.x, b.y, None, plan=False)
        queue = {1.0: 0, -1.0: 0}  # robots leaving by each touch line so far
        for b in sorted(everyone.ours, key=lambda b: b.id):
            if b.id in leaving:
                side = _substitution_side(b)
                out[b.id] = _substitution(b, inp.fs, queue[side])
                queue[side] += 1
        out = self._constrain(out, everyone)
        self.roles = {rid: it.role for rid, it in out.items()}
        return out

    def _choose_leaving(self, inp: StrategyInput) -> set[int]:
        """The robots to take off the field when the referee allows fewer than we have (a
        yellow or red card): the ones already on their way, then the nearest to a
        substitution spot, the keeper last. Robots leave by driving to within 1 m of where
        the halfway line meets a touch line, where the robot handler takes them out."""
        excess = 0 if inp.max_bots is None else len(inp.ours) - max(0, inp.max_bots)
        if excess <= 0:
            self.leaving = set()
            return set()
        visible = {b.id: b for b in inp.ours}
        keep = [i for i in sorted(self.leaving) if i in visible][:excess]

        def cost(b: Bot) -> tuple[bool, float]:
            return (b.id == inp.keeper_id, math.dist(b.xy, _substitution_spot(b, inp.fs)))
        rest = sorted((b for b in inp.ours if b.id not in keep), key=cost)
        self.leaving = set(keep) | {b.id for b in rest[: excess - len(keep)]}
        return self.leaving

    # ---- slots per play and situation ----

    def _slots(self, inp: StrategyInput) -> list[Slot]:
        sit, fs, ball, n = inp.situation, inp.fs, inp.ball, len(inp.ours)
        tu = inp.tuning
        if sit.kind == "timeout":
            return self._parked(n, fs)
        if inp.play == "formation":
            return self._formation(inp)
        if sit.kind in ("kickoff-prepare", "kickoff"):
            return self._kickoff(inp)
        if sit.kind in ("penalty-prepare", "penalty"):
            return self._penalty(inp)
        base = self._running(inp)
        if ball is None:
            return base
        if sit.kind in ("stop", "halt") or (sit.kind in ("free-kick", "placement")
                                            and not sit.ours):
            return [self._blocker(s, ball, fs, tu) if s.role == "attacker" else s for s in base]
        if sit.kind == "free-kick" and sit.ours:
            return [self._free_kicker(s, inp) if s.role == "attacker" else s for s in base]
        if sit.kind == "placement" and sit.ours and sit.designated is not None:
            dp = sit.designated

            def place(b: Bot) -> Intent:
                # the game is stopped: the defence area rules are for running play (and the
                # 0.2 m of STOP and free kicks), so the placer fetches a ball from either area
                return replace(_placer(b, ball, dp, tu, fs), own_defense_ok=True,
                               their_defense_ok=True)
            return [Slot("placer", "placer", ball.xy, place) if s.role == "attacker" else s
                    for s in base]
        return base

    def _running(self, inp: StrategyInput) -> list[Slot]:
        fs, ball, n, tu = inp.fs, inp.ball, len(inp.ours), inp.tuning
        play = inp.play
        blockers = [b.xy for b in inp.theirs]
        gk_make: Make
        if play == "simple":
            def gk_make(bot: Bot) -> Intent:
                return goalkeeper(ball, fs, None, 1e9, tu.pass_speed_mps, bot)
        else:
            def gk_make(bot: Bot) -> Intent:
                return goalkeeper(ball, fs, inp.keeper_point, tu.keeper_min_speed_mmps,
                                  tu.pass_speed_mps, bot)
        gk = Slot("goalkeeper", "goalkeeper", (-fs.half_length + R, 0.0), gk_make)
        slots = [gk]
        if n == 1:
            return slots
        n_rest = n - 1
        if play == "defend":
            n_def, n_att, n_sup = n_rest, 0, 0
        elif play == "attack-drill" or play == "simple":
            n_def, n_att, n_sup = 0, 1, n_rest - 1
        else:
            n_att = 1
            n_def = min(3, (n_rest - 1 + 1) // 2)
            n_sup = n_rest - 1 - n_def
        if n_att and ball is not None:
            if play == "simple":
                def att_make(bot: Bot) -> Intent:
                    return kick_ball(ball, (fs.half_length, 0.0), 4.0, "attacker", bot)
            else:
                def att_make(bot: Bot) -> Intent:
                    others = blockers + [b.xy for b in inp.ours if b.id != bot.id]
                    return attacker(ball, bot, others, fs, tu.kick_speed_mps, tu.pass_speed_mps)
            slots.append(Slot("attacker", "attacker", ball.xy, att_make))
        elif n_att:
            n_sup += n_att
        dpts = defender_points(n_def, ball, fs, tu.defense_margin_mm, tu.robot_margin_mm)
        if play == "simple":
            spts = [(-0.3 * fs.field_length, -0.25 * fs.field_width),
                    (-0.3 * fs.field_length, 0.25 * fs.field_width),
                    (-0.15 * fs.field_length, 0.0), (-0.35 * fs.field_length, 0.0),
                    (-0.15 * fs.field_length, 0.35 * fs.field_width)] * 3
            spts = spts[:n_sup]
        else:
            spts = supporter_points(n_sup, ball, fs)
        rest: list[Slot] = []
        face = 0.0
        d_slots = [Slot(f"defender-{k + 1}", "defender", p, _hold("defender", p, face))
                   for k, p in enumerate(dpts)]
        s_slots = [Slot(f"supporter-{k + 1}", "supporter", p, _hold("supporter", p, face))
                   for k, p in enumerate(spts)]
        # interleave by priority: defender, supporter, defender, ...
        for k in range(max(len(d_slots), len(s_slots))):
            if k < len(d_slots):
                rest.append(d_slots[k])
            if k < len(s_slots):
                rest.append(s_slots[k])
        return slots + rest

    @staticmethod
    def _blocker(s: Slot, ball: Ball, fs: Field, tu: Tuning) -> Slot:
        u = unit(-fs.half_length - ball.x, -ball.y)
        p = clamp_to_field((ball.x + u[0] * (tu.stop_distance_mm + 30.0),
                            ball.y + u[1] * (tu.stop_distance_mm + 30.0)), fs)
        face = math.atan2(ball.y - p[1], ball.x - p[0])
        return Slot("blocker", "blocker", p, _hold("blocker", p, face))

    @staticmethod
    def _free_kicker(s: Slot, inp: StrategyInput) -> Slot:
        ball, fs, tu = inp.ball, inp.fs, inp.tuning
        assert ball is not None
        sit = inp.situation

        def make(bot: Bot) -> Intent:
            others = [b.xy for b in inp.theirs] + [b.xy for b in inp.ours if b.id != bot.id]
            aim, angle = best_shot(ball.xy, others, fs)
            speed = tu.kick_speed_mps
            deep = fs.half_length - ball.x > 0.6 * fs.field_length
            if sit.indirect or angle < math.radians(3.0) or deep:
                # pass to the team mate furthest forward (or just forward)
                mates = [b for b in inp.ours if b.id != bot.id]
                if mates:
                    m = max(mates, key=lambda b: b.x)
                    aim = m.xy
                else:
                    aim = (ball.x + 2000.0, ball.y)
                speed = tu.pass_speed_mps
            return kick_ball(ball, aim, speed, "kicker", bot)
        return Slot("kicker", "kicker", ball.xy, make)

    def _kickoff(self, inp: StrategyInput) -> list[Slot]:
        fs, ball, n, tu, sit = inp.fs, inp.ball, len(inp.ours), inp.tuning, inp.situation
        cr = fs.center_circle_radius + R + 80.0
        slots = [Slot("goalkeeper", "goalkeeper", (-fs.half_length + R + 30.0, 0.0),
                      _hold("goalkeeper", (-fs.half_length + R + 30.0, 0.0), 0.0,
                            own_defense_ok=True))]
        bxy = ball.xy if ball is not None else (0.0, 0.0)
        if sit.ours and n > 1:
            make: Make
            if sit.kind == "kickoff" and ball is not None:
                def make(bot: Bot) -> Intent:
                    others = [b.xy for b in inp.theirs]
                    aim, _ = best_shot(ball.xy, others, fs)
                    return kick_ball(ball, aim, tu.kick_speed_mps, "kicker", bot)
            else:
                p = (bxy[0] - CONTACT_MM - R, bxy[1])
                make = _hold("kicker", p, 0.0)
            slots.append(Slot("kicker", "kicker", (bxy[0] - CONTACT_MM - R, bxy[1]), make))
        spots = [(-cr, 0.0)] if not sit.ours else []
        spots += [(-fs.half_length + fs.penalty_area_depth + 350.0, -500.0),
                  (-fs.half_length + fs.penalty_area_depth + 350.0, 500.0),
                  (-R - 100.0, -0.25 * fs.field_width), (-R - 100.0, 0.25 * fs.field_width),
                  (-0.25 * fs.field_length, 0.0), (-0.2 * fs.field_length, -0.35 * fs.field_width),
                  (-0.2 * fs.field_length, 0.35 * fs.field_width), (-cr, 0.6 * cr),
                  (-cr, -0.6 * cr),
                  (-0.35 * fs.field_length, 0.3 * fs.field_width),
                  (-0.35 * fs.field_length, -0.3 * fs.field_width)]
        for k, p in enumerate(spots[: max(0, n - len(slots))]):
            role = "blocker" if (not sit.ours and k == 0) else "kickoff"
            slots.append(Slot(f"kickoff-{k + 1}", role, p, _hold(role, p, 0.0)))
        return slots

    def _penalty(self, inp: StrategyInput) -> list[Slot]:
        fs, ball, n, tu, sit = inp.fs, inp.ball, len(inp.ours), inp.tuning, inp.situation
        bxy = ball.xy if ball is not None else (0.0, 0.0)
        slots: list[Slot] = []
        if sit.ours:
            gk = (-fs.half_length + R + 30.0, 0.0)
            slots.append(Slot("goalkeeper", "goalkeeper", gk,
                              _hold("goalkeeper", gk, 0.0, own_defense_ok=True)))
            if n > 1:
                make: Make
                if sit.kind == "penalty" and ball is not None:
                    def make(bot: Bot) -> Intent:
                        aim, _ = best_shot(ball.xy, [b.xy for b in inp.theirs], fs)
                        return kick_ball(ball, aim, tu.kick_speed_mps, "kicker", bot)
                else:
                    p = (bxy[0] - CONTACT_MM - 150.0, bxy[1])
                    make = _hold("kicker", p, 0.0)
                slots.append(Slot("kicker", "kicker", bxy, make))
            line_x = bxy[0] - 1000.0 - R - 150.0
        else:
            gx = -fs.half_length + R * 0.5
            gy = max(-fs.goal_width / 2 + R, min(fs.goal_width / 2 - R, bxy[1]))
            slots.append(Slot("goalkeeper", "goalkeeper", (gx, gy),
                              _hold("goalkeeper", (gx, gy), 0.0, own_defense_ok=True)))
            line_x = bxy[0] + 1000.0 + R + 150.0
        m = n - len(slots)
        line_x = max(-fs.half_length + R + 50.0, min(fs.half_length - R - 50.0, line_x))
        ys = _free_ys(m, fs, line_x, [b.xy for b in inp.theirs])
        for k, y in enumerate(ys):
            p = (line_x, y)
            slots.append(Slot(f"penalty-{k + 1}", "waiting", p, _hold("waiting", p, 0.0)))
        return slots

    @staticmethod
    def _parked(n: int, fs: Field) -> list[Slot]:
        y = -fs.half_width + R + 150.0
        slots = []
        for k in range(n):
            p = (-fs.half_length + 600.0 + k * 3.0 * R, y)
            slots.append(Slot(f"parked-{k + 1}", "parked", p,
                              _hold("parked", p, math.pi / 2, max_speed_mps=1.0)))
        return slots

    def _formation(self, inp: StrategyInput) -> list[Slot]:
        fs = inp.fs
        cfg = FormationConfig(period_s=inp.tuning.formation_period_s,
                              field_length_mm=fs.field_length, field_width_mm=fs.field_width,
                              own_half_sign=-1)
        pts = formation(int(inp.t // cfg.period_s), len(inp.ours), cfg)
        return [Slot(f"formation-{k + 1}", "formation", p, _hold("formation", p, 0.0))
                for k, p in enumerate(pts)]

    # ---- rules every play obeys ----

    def _constrain(self, out: dict[int, Intent], inp: StrategyInput) -> dict[int, Intent]:
        sit, ball, fs, tu = inp.situation, inp.ball, inp.fs, inp.tuning
        bots = {b.id: b for b in inp.ours}
        if sit.kind == "halt":
            return {rid: Intent(it.role, bots[rid].x, bots[rid].y, None, plan=False)
                    for rid, it in out.items()}
        keep_off = sit.kind == "stop" or (
            not sit.ours and sit.kind in ("free-kick", "placement", "kickoff-prepare",
                                          "kickoff"))
        capsule = sit.designated if sit.kind == "placement" and not sit.ours else None
        res: dict[int, Intent] = {}
        for rid, it in out.items():
            p = (it.x, it.y)
            if ball is not None and keep_off:
                d = tu.stop_distance_mm
                p = (push_out_of_capsule(p, ball.xy, capsule, d) if capsule is not None
                     else push_out_of_circle(p, ball.xy, d))
                p = _inside_field_off_ball(p, ball.xy, capsule, d, fs)
                it = replace(it, kick_speed_mps=0.0, avoid_ball_mm=d - 20.0, plan=True)
            if sit.kind in ("kickoff-prepare", "kickoff", "penalty-prepare", "penalty") \
                    and it.role != "kicker" and ball is not None:
                # only the kicker may touch the ball: everyone else plans around it
                it = replace(it, avoid_ball_mm=max(it.avoid_ball_mm, 400.0))
            if sit.kind in ("kickoff-prepare", "penalty-prepare") and it.role == "kicker" \
                    and ball is not None:
                # the kicker goes round the ball to its spot behind it: from the far side it
                # drove through the ball and pushed it off the mark (the GC's division B
                # penalty mark is in our half, among our robots; the GC then refused)
                it = replace(it, avoid_ball_mm=max(it.avoid_ball_mm, CONTACT_MM + 60.0),
                             plan=True)
            if sit.kind == "stop":
                it = replace(it, kick_speed_mps=0.0,
                             max_speed_mps=min(1.2, it.max_speed_mps or 1.2))
            if it.role == "goalkeeper":
                p = clamp_to_field(p, fs, inside=R * 0.5)  # the goal line is its place
            elif it.role != "placer":
                p = clamp_to_field(p, fs)
            res[rid] = it.moved(p[0], p[1])
        return res


def _substitution_side(bot: Bot) -> float:
    return 1.0 if bot.y >= 0.0 else -1.0


#: a second robot leaving by the same touch line waits this far behind the first (two
#: robots sent to one point: the second's goal is taken and it never arrives)
SUBSTITUTION_GAP_MM = 2.0 * R + 100.0


def _substitution_spot(bot: Bot, fs: Field, place: int = 0) -> tuple[float, float]:
    """On our side of the halfway line, by the touch line nearer the robot, inside the
    field and well within the rules' 1 m of where the halfway line meets it; the
    ``place``-th robot leaving by that touch line (0 = first) further along it."""
    return (-(R + 200.0) - place * SUBSTITUTION_GAP_MM,
            _substitution_side(bot) * (fs.half_width - R - 20.0))


def _substitution(bot: Bot, fs: Field, place: int = 0) -> Intent:
    p = _substitution_spot(bot, fs, place)
    return Intent("substitution", p[0], p[1], None, max_speed_mps=1.5)


def _inside_field_off_ball(p: tuple[float, float], ball: tuple[float, float],
                           mark: tuple[float, float] | None, d: float,
                           fs: Field) -> tuple[float, float]:
    """``p`` if it is in the field; else the nearest point in the field that still keeps
    ``d`` from the ball (and the corridor to ``mark``): pushing out of the ball's circle
    near a line would otherwise put the target outside, and clamping it back inside."""
    q = clamp_to_field(p, fs)
    if q == p:
        return p

    def clear(c: tuple[float, float]) -> bool:
        if mark is None:
            return math.dist(c, ball) >= d - 1e-6
        return math.dist(push_out_of_capsule(c, ball, mark, d), c) < 1e-6

    if clear(q):
        return q
    best: tuple[float, float] | None = None
    for k in range(36):
        for r in (d + 1.0, d + 150.0, d + 400.0):
            a = 2.0 * math.pi * k / 36
            c = clamp_to_field((ball[0] + r * math.cos(a), ball[1] + r * math.sin(a)), fs)
            if clear(c) and (best is None or math.dist(c, p) < math.dist(best, p)):
                best = c
    return best if best is not None else q


def _free_ys(m: int, fs: Field, x: float, others: Sequence[tuple[float, float]],
             ) -> list[float]:
    """``m`` spots along the line at ``x``, spread as ``_spread_ys`` does but moved off the
    other team's robots standing on or near that line (both teams line up behind the ball
    at a penalty: the same spots would leave our robots stuck in front of theirs)."""
    spread = _spread_ys(m, fs)
    near = [oy for ox, oy in others if abs(ox - x) < 2.0 * R + 100.0]
    if not near:
        return spread
    gap = 2.0 * R + 100.0
    lim = fs.half_width - R - 100.0
    free = [k * 50.0 for k in range(-int(lim // 50.0), int(lim // 50.0) + 1)
            if all(abs(k * 50.0 - oy) >= gap for oy in near)]
    out: list[float] = []
    for want in spread:  # each wanted spot takes the nearest free one not too near ours
        options = [y for y in free if all(abs(y - o) >= gap for o in out)]
        if not options:
            break
        out.append(min(options, key=lambda y: abs(y - want)))
    return sorted(out) + spread[len(out):]


def _spread_ys(m: int, fs: Field) -> list[float]:
    if m <= 0:
        return []
    span = fs.field_width - 2 * (R + 300.0)
    step = min(450.0, span / max(1, m - 1))
    return [(k - (m - 1) / 2.0) * step for k in range(m)]


#: the ball counts as placed this close to the mark (the rules allow 0.15 m)
PLACED_MM = 70.0


def _placer(bot: Bot, ball: Ball, dp: tuple[float, float], tu: Tuning,
            fs: Field | None = None) -> Intent:
    """Our ball placement: get behind the ball as seen from the mark, switch the dribbler on,
    carry the ball to the mark slowing down on the way (a released ball rolls on), wait
    until ball and robot are still, then let go and back off slowly. When there is no room
    behind the ball (it lies against the boundary wall), the placer takes the ball from the
    mark's side and pulls it, driving backwards."""
    to_mark = math.dist(ball.xy, dp)
    pull = False
    if fs is not None and to_mark >= PLACED_MM:
        d0 = unit(dp[0] - ball.x, dp[1] - ball.y)
        bx = ball.x - d0[0] * (CONTACT_MM + 120.0)
        by = ball.y - d0[1] * (CONTACT_MM + 120.0)
        pull = abs(bx) > fs.half_length + 120.0 or abs(by) > fs.half_width + 120.0
        # a ball already held for pulling is pulled all the way: going round it to push,
        # once there is room behind it, would cost many seconds of the 30 allowed
        pull = pull or _pull_hold(bot, ball, dp)
    if pull:
        return _puller(bot, ball, dp, tu, to_mark)
    held = math.dist(bot.xy, ball.xy) < CONTACT_MM + 40.0
    bot_speed = math.hypot(bot.vx, bot.vy)
    if to_mark < PLACED_MM or (held and to_mark < 2 * PLACED_MM and bot_speed < 150.0):
        if held and bot_speed > 60.0:
            # still moving: hold the ball and stand (the dribbler keeps it)
            return Intent("placer", bot.x, bot.y, bot.orientation, dribbler=True,
                          max_speed_mps=0.2, plan=False)
        away = unit(bot.x - ball.x, bot.y - ball.y)
        p = (ball.x + away[0] * (CONTACT_MM + 550.0), ball.y + away[1] * (CONTACT_MM + 550.0))
        face = math.atan2(ball.y - p[1], ball.x - p[0])
        return Intent("placer", p[0], p[1], face, max_speed_mps=0.4 if held else 1.0,
                      avoid_ball_mm=0.0 if held else CONTACT_MM + 60.0, plan=not held)
    d = unit(dp[0] - ball.x, dp[1] - ball.y)
    face = math.atan2(d[1], d[0])
    rx, ry = ball.x - bot.x, ball.y - bot.y
    along = rx * d[0] + ry * d[1]
    across = abs(-rx * d[1] + ry * d[0])
    heading_err = abs(wrap_angle(bot.orientation - face))
    if 0.0 < along < CONTACT_MM + 60.0 and across < 40.0 and heading_err < 0.25:
        # holding the ball: carry it so that it ends on the mark, braking on the way
        goal = (dp[0] - d[0] * CONTACT_MM, dp[1] - d[1] * CONTACT_MM)
        brake = math.sqrt(2.0 * 0.5 * max(0.0, to_mark - 20.0) / 1000.0)
        return Intent("placer", goal[0], goal[1], face, dribbler=True,
                      max_speed_mps=max(0.1, min(tu.placement_speed_mps, brake)), plan=False)
    if 0.0 < along < CONTACT_MM + 200.0 and across < 40.0 and heading_err < 0.25:
        # aligned behind the ball: roll onto it slowly with the dribbler on
        return Intent("placer", ball.x - d[0] * (CONTACT_MM - 10.0),
                      ball.y - d[1] * (CONTACT_MM - 10.0), face, dribbler=True,
                      max_speed_mps=0.5, plan=False)
    behind = (ball.x - d[0] * (CONTACT_MM + 120.0), ball.y - d[1] * (CONTACT_MM + 120.0))
    return Intent("placer", behind[0], behind[1], face, avoid_ball_mm=CONTACT_MM + 60.0,
                  max_speed_mps=1.5)


def _pull_pose(bot: Bot, ball: Ball, dp: tuple[float, float]) -> tuple[float, float, float]:
    """(along, across, heading error) of a robot facing the ball from the mark's side."""
    d = unit(dp[0] - ball.x, dp[1] - ball.y)
    face = math.atan2(-d[1], -d[0])  # towards the ball, away from the mark
    rx, ry = ball.x - bot.x, ball.y - bot.y
    along = -(rx * d[0] + ry * d[1])  # how far the robot is on the mark's side of the ball
    across = abs(-rx * d[1] + ry * d[0])
    heading_err = abs(wrap_angle(bot.orientation - face))
    return along, across, heading_err


def _pull_hold(bot: Bot, ball: Ball, dp: tuple[float, float]) -> bool:
    """Whether the placer holds the ball for pulling: at the ball from the mark's side, facing
    it, and (for a robot that reports it) with the ball at its dribbler. Backing up before the
    dribbler has the ball leaves the ball behind, and the placer comes back for it: seen as a
    robot oscillating 40-60 mm in front of the ball for the whole 30 s, more often when the
    filtered position lags a little. With no word from the robot, the positions decide."""
    along, across, heading_err = _pull_pose(bot, ball, dp)
    if bot.contact is not None:
        return bot.contact and 0.0 < along < CONTACT_MM + 120.0 and heading_err < 0.5
    return 0.0 < along < CONTACT_MM + 60.0 and across < 40.0 and heading_err < 0.25


def _puller(bot: Bot, ball: Ball, dp: tuple[float, float], tu: Tuning,
            to_mark: float) -> Intent:
    """Ball placement by pulling: face the ball from the mark's side, dribble, back up."""
    d = unit(dp[0] - ball.x, dp[1] - ball.y)
    face = math.atan2(-d[1], -d[0])  # towards the ball, away from the mark
    along, across, heading_err = _pull_pose(bot, ball, dp)
    if _pull_hold(bot, ball, dp):
        goal = (dp[0] + d[0] * CONTACT_MM, dp[1] + d[1] * CONTACT_MM)
        brake = math.sqrt(2.0 * 0.5 * max(0.0, to_mark - 20.0) / 1000.0)
        return Intent("placer", goal[0], goal[1], face, dribbler=True,
                      max_speed_mps=max(0.1, min(0.5, tu.placement_speed_mps, brake)),
                      plan=False)
    if 0.0 < along < CONTACT_MM + 200.0 and across < 40.0 and heading_err < 0.25:
        return Intent("placer", ball.x + d[0] * (CONTACT_MM - 10.0),
                      ball.y + d[1] * (CONTACT_MM - 10.0), face, dribbler=True,
                      max_speed_mps=0.4, plan=False)
    front = (ball.x + d[0] * (CONTACT_MM + 120.0), ball.y + d[1] * (CONTACT_MM + 120.0))
    return Intent("placer", front[0], front[1], face, avoid_ball_mm=CONTACT_MM + 60.0,
                  max_speed_mps=1.5)
