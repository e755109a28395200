import math

from backend.control.goto import GoToConfig, GoToController, Target, global_to_local


def simulate(ctrl: GoToController, x: float, y: float, th: float, tgt: Target, steps: int,
             dt: float = 0.01) -> tuple[float, float, float, float]:
    vmax_seen = 0.0
    for _ in range(steps):
        v = ctrl.step(x, y, th, tgt, dt)
        c, s = math.cos(th), math.sin(th)
        vx = v.forward_mps * c - v.left_mps * s
        vy = v.forward_mps * s + v.left_mps * c
        vmax_seen = max(vmax_seen, math.hypot(vx, vy))
        x += vx * dt * 1000
        y += vy * dt * 1000
        th += v.angular_radps * dt
    return x, y, th, vmax_seen


def test_reaches_the_target_within_tolerance_and_respects_the_speed_limit() -> None:
    cfg = GoToConfig(max_speed_mps=1.5)
    x, y, th, vmax = simulate(GoToController(cfg), 0, 0, 0.7, Target(2000, -1000, 1.0), 600)
    assert math.hypot(x - 2000, y + 1000) <= cfg.position_tolerance_mm + 5
    assert abs(math.atan2(math.sin(th - 1.0), math.cos(th - 1.0))) < 0.05
    assert vmax <= 1.5 + 1e-9


def test_acceleration_limit_holds_from_rest() -> None:
    cfg = GoToConfig(max_accel_mps2=2.0)
    c = GoToController(cfg)
    v = c.step(0, 0, 0, Target(3000, 0, None), 0.01)
    assert math.hypot(v.forward_mps, v.left_mps) <= 2.0 * 0.01 + 1e-9


def test_local_frame_rotation() -> None:
    fwd, left = global_to_local(1.0, 0.0, math.pi / 2)  # facing +y, moving +x: to the right
    assert math.isclose(fwd, 0.0, abs_tol=1e-12) and math.isclose(left, -1.0)
