import itertools
import math

import pytest

from backend.control.goto import LocalVelocity, Target
from backend.control.motion import (
    PHASE_BLOCKED,
    PHASE_HOLD,
    PHASE_LOST,
    TELEMETRY_KEYS,
    Algorithm1,
    Algorithm2,
    MotionBank,
    Proportional,
    RobotMotion,
    RobotMotionState,
    make_controller,
)
from backend.control.params import ALGORITHMS, ControllerParams, ControlSettings
from tests.backend.control.sim import Plant, drive

DT = 1 / 60
B = Target(3000.0, 0.0, 0.0)


@pytest.mark.parametrize("true_c", [0.6, 0.8, 1.0, 1.25, 1.6])
def test_c_estimate_converges_to_the_true_gain(true_c: float) -> None:
    ctrl = Algorithm1()
    plant = Plant(gain=true_c)
    # back and forth: the estimate is the robot's property and survives new targets
    for i in range(6):
        drive(ctrl, plant, Target(3000.0 if i % 2 == 0 else 0.0, 0.0, 0.0), 6.0)
    assert ctrl.c_estimate == pytest.approx(true_c, rel=0.03)


def test_algorithm1_tracks_the_trapezoid_and_arrives_on_time_whatever_c() -> None:
    arrivals = []
    for c in (0.6, 1.0, 1.4):
        ctrl = Algorithm1()
        plant = Plant(gain=c)
        for i in range(4):  # learn C first
            drive(ctrl, plant, Target(3000.0 if i % 2 == 0 else 0.0, 0.0, 0.0), 6.0)
        t = 0.0
        while abs(plant.x_mm - 3000.0) > 20.0 and t < 10.0:
            plant.apply(ctrl.step(plant.state(), B, DT), DT)
            t += DT
        arrivals.append(t)
        drive(ctrl, plant, B, 3.0)
        assert plant.x_mm == pytest.approx(3000.0, abs=12.0)
    assert max(arrivals) - min(arrivals) < 0.1
    assert arrivals[0] == pytest.approx(10 / 3, abs=0.2)  # T = D/v + v/w


def test_algorithm1_reference_respects_v_and_w() -> None:
    ctrl = Algorithm1()
    plant = Plant(gain=1.0)
    refs = []
    for _ in range(300):
        plant.apply(ctrl.step(plant.state(), B, DT), DT)
        refs.append(ctrl.telemetry()["ref_x_m"])
    speeds = [(b - a) / DT for a, b in itertools.pairwise(refs)]
    assert max(speeds) <= 1.0 + 1e-9
    assert max(abs(b - a) / DT for a, b in itertools.pairwise(speeds)) <= 3.0 + 1e-6


def test_algorithm2_speed_follows_sqrt_2aS_within_the_limits() -> None:
    p = ControllerParams()
    a, v, w = p.algorithm2.a_mps2, p.algorithm2.v_mps, p.algorithm2.w_mps2
    ctrl = Algorithm2()
    plant = Plant(gain=1.0)
    prev = 0.0
    for _ in range(400):
        s = (3000.0 - plant.x_mm) / 1000.0
        vx, _ = plant.apply(ctrl.step(plant.state(), B, DT), DT)
        assert vx <= v + 1e-9
        assert abs(vx - prev) <= w * DT + 1e-9
        assert vx <= math.sqrt(2 * a * max(s, 0.0)) + 1e-9  # never faster than the curve
        if s > 0.05 and vx < v - 1e-9 and abs(vx - prev) < w * DT - 1e-9:
            # not limited by v or w: exactly on the curve
            assert vx == pytest.approx(math.sqrt(2 * a * s), rel=1e-9)
        prev = vx
    assert plant.x_mm == pytest.approx(3000.0, abs=11.0)


def test_algorithm2_stores_only_the_last_speed() -> None:
    # two controllers, one fresh: same last command and same position -> same output
    c1, c2 = Algorithm2(), Algorithm2()
    plant = Plant()
    drive(c1, plant, B, 1.0)
    c2.handover(c1)
    st = plant.state()
    # same A for both: restart c1's move from the current position too
    c1.reset()
    c1.handover(c2)
    assert c1.step(st, B, DT) == c2.step(st, B, DT)


def test_new_target_restarts_the_profile_from_the_current_position_and_keeps_c() -> None:
    ctrl = Algorithm1()
    plant = Plant(gain=0.8)
    drive(ctrl, plant, B, 6.0)
    c = ctrl.c_estimate
    assert c != pytest.approx(1.0)
    x_before = plant.x_mm
    ctrl.step(plant.state(), Target(x_before, 2000.0, 0.0), DT)
    tel = ctrl.telemetry()
    assert tel["x_m"] == pytest.approx(0.0, abs=1e-9)  # A is where the robot is
    assert tel["path_length_m"] == pytest.approx(2.0, abs=1e-3)
    assert tel["t_s"] == pytest.approx(DT)
    assert ctrl.c_estimate == pytest.approx(c, abs=1e-3)
    assert tel["restarts"] == 1


def test_small_target_move_keeps_a_and_time() -> None:
    ctrl = Algorithm1()
    plant = Plant()
    drive(ctrl, plant, B, 1.0)
    t = ctrl.telemetry()["t_s"]
    ctrl.step(plant.state(), Target(3020.0, 0.0, 0.0), DT)
    tel = ctrl.telemetry()
    assert tel["t_s"] == pytest.approx(t + DT)
    assert tel["path_length_m"] == pytest.approx(3.02, abs=1e-6)
    assert tel["restarts"] == 0


def test_blocked_robot_restarts_the_profile_and_c_stays_sane() -> None:
    ctrl = Algorithm1()
    plant = Plant(gain=1.0)
    drive(ctrl, plant, B, 1.0)
    plant.blocked = True
    phases = []
    for _ in range(round(3.0 / DT)):
        plant.apply(ctrl.step(plant.state(), B, DT), DT)
        phases.append(ctrl.telemetry()["phase"])
    assert PHASE_BLOCKED in phases
    assert ctrl.telemetry()["restarts"] >= 2
    p = ControllerParams().algorithm1
    assert p.c_min <= ctrl.c_estimate <= p.c_max
    assert ctrl.c_estimate > 0.7  # a wall is not a slow robot
    plant.blocked = False
    drive(ctrl, plant, B, 6.0)
    assert plant.x_mm == pytest.approx(3000.0, abs=12.0)


def test_c_estimate_is_clamped() -> None:
    ctrl = Algorithm1()
    plant = Plant(gain=20.0)  # far outside the sane range
    for i in range(4):
        drive(ctrl, plant, Target(3000.0 if i % 2 == 0 else 0.0, 0.0, 0.0), 4.0)
    assert ctrl.c_estimate <= ControllerParams().algorithm1.c_max


def test_lost_robot_commands_zero_and_restarts_where_it_is_seen_again() -> None:
    ctrl = Algorithm1()
    plant = Plant()
    drive(ctrl, plant, B, 1.0)
    lost = RobotMotionState(0.0, 0.0, 0.0, visible=False)
    assert ctrl.step(lost, B, DT) == LocalVelocity.zero()
    assert ctrl.telemetry()["phase"] == PHASE_LOST
    plant.x_mm += 500.0  # moved while not seen
    ctrl.step(plant.state(), B, DT)
    tel = ctrl.telemetry()
    assert tel["x_m"] == pytest.approx(0.0, abs=1e-9)
    assert tel["path_length_m"] == pytest.approx((3000.0 - plant.x_mm) / 1000.0, abs=1e-6)


def test_a_stop_during_a_move_counts_as_a_restart_and_an_idle_one_does_not() -> None:
    """A move stopped (HALT, lost vision, a stalled strategy: the station resets every
    controller) starts again from where the robot is: a restart, as after it was lost (the
    telemetry's line is then shorter than the way; a test read that as a wrong line)."""
    ctrl = Algorithm1()
    plant = Plant()
    drive(ctrl, plant, B, 1.0)
    before = ctrl.telemetry()["restarts"]
    ctrl.reset()
    ctrl.reset()  # (every tick of the stop resets again)
    ctrl.step(plant.state(), B, DT)
    tel = ctrl.telemetry()
    assert tel["restarts"] == before + 1
    assert tel["path_length_m"] == pytest.approx((3000.0 - plant.x_mm) / 1000.0, abs=1e-6)
    idle = Algorithm1()
    idle.reset()
    idle.step(Plant().state(), B, DT)
    assert idle.telemetry()["restarts"] == 0  # nothing was under way


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_heading_control_turns_to_the_target_orientation_within_limits(algorithm: str) -> None:
    ctrl = make_controller(algorithm)  # type: ignore[arg-type]
    plant = Plant(theta=-2.5)
    lim = ControllerParams().limits.max_angular_radps
    for _ in range(round(4.0 / DT)):
        v = ctrl.step(plant.state(), Target(0.0, 0.0, 2.0), DT)
        assert abs(v.angular_radps) <= lim + 1e-9
        plant.apply(v, DT)
    err = math.atan2(math.sin(plant.theta - 2.0), math.cos(plant.theta - 2.0))
    assert abs(err) <= ControllerParams().heading.tolerance_rad + 1e-9
    # the short way round: -2.5 -> 2.0 is 1.78 rad clockwise, not 4.5 rad ccw
    v = make_controller(algorithm).step(  # type: ignore[arg-type]
        RobotMotionState(0.0, 0.0, -2.5), Target(0.0, 0.0, 2.0), DT)
    assert v.angular_radps < 0.0


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_drives_sideways_to_a_target_in_the_robot_frame(algorithm: str) -> None:
    ctrl = make_controller(algorithm)  # type: ignore[arg-type]
    plant = Plant(theta=math.pi / 2)  # facing +y: the target at +x is to the right
    v = LocalVelocity.zero()
    for _ in range(10):
        v = ctrl.step(plant.state(), Target(1000.0, 0.0, None), DT)
    assert v.left_mps < 0.0 and abs(v.forward_mps) < 1e-9
    drive(ctrl, plant, Target(1000.0, 0.0, None), 5.0)
    assert math.hypot(plant.x_mm - 1000.0, plant.y_mm) <= 15.0


def test_lateral_correction_brings_the_robot_back_to_the_line() -> None:
    ctrl = Algorithm2()
    plant = Plant()
    ctrl.step(plant.state(), B, DT)  # A = (0, 0)
    plant.y_mm = 200.0  # pushed off the line
    max_left = 0.0
    for _ in range(round(1.5 / DT)):
        v = ctrl.step(plant.state(), B, DT)
        plant.apply(v, DT)
        max_left = min(max_left, v.left_mps)
    assert abs(plant.y_mm) < 20.0
    assert max_left >= -ControllerParams().lateral.max_mps - 1e-9


@pytest.mark.parametrize("order", [("algorithm1", "algorithm2"), ("algorithm2", "algorithm1"),
                                   ("algorithm2", "proportional"), ("proportional", "algorithm1"),
                                   ("algorithm1", "proportional")])
def test_switching_algorithm_never_jumps_beyond_the_acceleration_limit(
        order: tuple[str, str]) -> None:
    params = ControllerParams()
    motion = RobotMotion(order[0], params)  # type: ignore[arg-type]
    plant = Plant(gain=0.8)
    prev = (0.0, 0.0)
    max_dv = params.limits.max_accel_mps2 * DT + 1e-9
    for i in range(round(5.0 / DT)):
        if i == round(1.5 / DT):
            motion.configure(order[1], params)  # type: ignore[arg-type]
            assert motion.algorithm == order[1]
        v = motion.step(plant.state(), B, DT)
        cur = plant.apply(v, DT)
        assert math.hypot(cur[0] - prev[0], cur[1] - prev[1]) <= max_dv
        prev = cur
    drive(motion, plant, B, 4.0)
    assert plant.x_mm == pytest.approx(3000.0, abs=15.0)


def test_c_estimate_survives_a_switch() -> None:
    motion = RobotMotion("algorithm1")
    plant = Plant(gain=0.7)
    drive(motion, plant, B, 6.0)
    c = motion.telemetry()["c_estimate"]
    motion.configure("algorithm2", ControllerParams())
    motion.configure("algorithm1", ControllerParams())
    assert motion.telemetry()["c_estimate"] == c


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_telemetry_has_every_key_and_finite_values(algorithm: str) -> None:
    ctrl = make_controller(algorithm)  # type: ignore[arg-type]
    assert set(ctrl.telemetry()) == set(TELEMETRY_KEYS)
    drive(ctrl, Plant(), B, 5.0)
    tel = ctrl.telemetry()
    assert set(tel) == set(TELEMETRY_KEYS)
    assert all(math.isfinite(v) for v in tel.values())
    assert tel["phase"] == PHASE_HOLD
    assert tel["x_m"] == pytest.approx(3.0, abs=0.012)


def test_reset_commands_from_zero_again() -> None:
    ctrl = Algorithm2()
    plant = Plant()
    drive(ctrl, plant, B, 1.0)
    ctrl.reset()
    v = ctrl.step(plant.state(), B, DT)
    assert math.hypot(v.forward_mps, v.left_mps) <= ControllerParams().algorithm2.w_mps2 * DT + 1e-9


def test_proportional_baseline_reaches_the_target() -> None:
    ctrl = Proportional()
    plant = Plant()
    drive(ctrl, plant, Target(-1500.0, 800.0, None), 6.0)
    assert math.hypot(plant.x_mm + 1500.0, plant.y_mm - 800.0) <= 15.0


def test_motion_bank_applies_per_robot_settings() -> None:
    settings = ControlSettings.model_validate({
        "default_algorithm": "algorithm2",
        "robots": {"blue/3": {"algorithm": "algorithm1", "v_mps": 1.5, "k_per_s": 2.0}},
    })
    bank = MotionBank(settings)
    assert bank.get("blue", 3).algorithm == "algorithm1"
    assert bank.get("blue", 3).controller.params.algorithm1.v_mps == 1.5
    assert bank.get("blue", 3).controller.params.algorithm1.k_per_s == 2.0
    assert bank.get("blue", 4).algorithm == "algorithm2"
    assert bank.get("blue", 4).controller.params.algorithm1.v_mps == 1.0
    bank.apply_settings(ControlSettings(default_algorithm="proportional"))
    assert bank.get("blue", 3).algorithm == "proportional"
    assert set(bank.telemetry()) == {"blue/3", "blue/4"}
