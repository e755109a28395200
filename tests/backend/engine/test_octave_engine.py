"""OctaveEngine against GNU Octave: the example scripts, file.function calls, value
conversion, and the same failure handling as the numpy engine. Skipped only when Octave is
not installed."""

from __future__ import annotations

import math
import time
from collections.abc import AsyncIterator
from pathlib import Path

import numpy as np
import pytest

from backend import geometry as g
from backend.engine import (
    EngineError,
    EngineTimeout,
    EngineWorkerDied,
    OctaveEngine,
    find_octave,
)

pytestmark = pytest.mark.skipif(
    find_octave() is None,
    reason="GNU Octave (octave-cli) is not installed: "
           "apt-get install --no-install-recommends octave")

ROOT = Path(__file__).resolve().parents[3]
SCRIPTS = ROOT / "engine_scripts"
TEST_M = Path(__file__).resolve().parent / "m"


@pytest.fixture
async def octave() -> AsyncIterator[OctaveEngine]:
    eng = OctaveEngine(SCRIPTS, extra_paths=[TEST_M], workers=1, default_timeout_s=10.0)
    await eng.start()
    try:
        yield eng
    finally:
        await eng.close()


async def test_goalkeeper_script_matches_numpy(octave: OctaveEngine) -> None:
    rng = np.random.default_rng(7)
    balls = rng.uniform(-4500, 4500, size=(50, 2))
    vels = rng.uniform(-5000, 5000, size=(50, 2))
    vels[:5, 0] = 0.0  # not moving along x
    vels[5:10, 0] = 50.0  # slower than min_speed
    for margin in (0.0, 90.0):
        remote = await octave.call("goalkeeper", balls, vels, -4500.0, 1000.0, margin, 100.0)
        local = g.goalkeeper_target(balls, vels, -4500.0, 1000.0, margin, 100.0)
        assert remote.shape == (50, 2)
        np.testing.assert_allclose(remote, local, rtol=1e-12, atol=1e-9)
    one = await octave.call("goalkeeper", np.array([0.0, 0.0]), np.array([-1000.0, 91.111]),
                            -4500.0, 1000.0)
    np.testing.assert_allclose(one, [[-4500.0, 409.9995]])  # default margin and min_speed


async def test_geometry_src_functions_by_file_dot_function(octave: OctaveEngine) -> None:
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(22, 2)) * 1000, rng.normal(size=(22, 2)) * 1000
    ang = await octave.call("geometry_src.get_angle", a, b)
    np.testing.assert_allclose(ang.ravel(), g.signed_angle(a, b), atol=1e-12)
    d = await octave.call("geometry_src.distance", a, b)
    np.testing.assert_allclose(d.ravel(), g.distance(a, b), rtol=1e-12)
    th = rng.uniform(-10, 10, size=(22, 1))
    rot = await octave.call("geometry_src.rotate_2d", a, th)
    np.testing.assert_allclose(rot, g.rotate(a, th[:, 0]), rtol=1e-12, atol=1e-9)
    w = await octave.call("geometry_src.wrap_angle", th)
    np.testing.assert_allclose(w.ravel(), g.wrap_angle(th[:, 0]), atol=1e-12)
    p = rng.normal(size=(22, 2)) * 1000
    sd = await octave.call("geometry_src.point_segment_distance", p, a, b)
    np.testing.assert_allclose(sd.ravel(), g.point_segment_distance(p, a, b), rtol=1e-9)
    cart = await octave.call("geometry_src.to_cartesian", 2.0, math.pi / 2)
    np.testing.assert_allclose(cart, [[0.0, 2.0]], atol=1e-12)
    # two outputs; Octave's index is 1-based
    pt, idx = await octave.call("geometry_src.select_closest_point", a, np.array([0.0, 0.0]),
                                nargout=2)
    k = int(np.argmin(g.norm(a)))
    assert idx == k + 1 and np.array_equal(pt, a[k:k + 1])


async def test_segment_circle_hit_script_matches_numpy(octave: OctaveEngine) -> None:
    rng = np.random.default_rng(11)
    centers = rng.uniform(-3000, 3000, size=(8, 2))
    radii = rng.uniform(90, 600, size=8)
    for _ in range(20):
        a, b = rng.uniform(-4000, 4000, size=(2, 2))
        hit, first = await octave.call("geometry_src.segment_circle_hit", a, b, centers, radii,
                                       nargout=2)
        res = g.segment_hits_circles(a, b, centers, radii)
        assert hit == bool(res.hit)
        assert int(first) == int(res.first) + 1  # 0 when none, else 1-based


async def test_struct_export_and_missing_names(octave: OctaveEngine) -> None:
    assert await octave.call("struct_src.twice", 21.0) == 42.0
    assert await octave.call("struct_src.hidden_name", 1.0) == 0.0
    with pytest.raises(EngineError, match=r"exports no function nope .*get_angle"):
        await octave.call("geometry_src.nope", 1.0)
    with pytest.raises(EngineError, match=r"no function file nofile\.m"):
        await octave.call("nofile.f")
    with pytest.raises(EngineError, match="must return a cell array or struct"):
        await octave.call("answer.x")
    with pytest.raises(EngineError, match=r"calling class_of\(\) for the functions it exports"):
        await octave.call("class_of.x")
    with pytest.raises(ValueError, match="not an Octave function name"):
        await octave.call("system('ls')")


async def test_value_conversions_round_trip(octave: OctaveEngine) -> None:
    m = np.arange(6.0).reshape(2, 3)
    out = await octave.call("identity", 1.5, True, "text é", m, np.array([True, False]),
                            [1.0, "a", [2.0]], {"k": 3.0, "s": "v"}, None, np.arange(3),
                            nargout=9)
    assert out[0] == 1.5 and out[1] is True and out[2] == "text é"
    assert np.array_equal(out[3], m) and out[3].dtype == np.float64
    assert out[4].tolist() == [[True, False]]
    assert out[5] == [1.0, "a", [2.0]]
    assert out[6] == {"k": 3.0, "s": "v"}
    assert out[7].shape == (0, 0)
    assert out[8].tolist() == [[0.0, 1.0, 2.0]]  # 1-D arrays travel as 1 x n rows
    assert await octave.call("class_of", np.zeros((3, 2))) == "double [3 2]"
    assert await octave.call("class_of", 7) == "double [1 1]"
    assert await octave.call("class_of", [1.0]) == "cell [1 1]"
    assert await octave.call("int32", 7.0) == 7.0
    assert await octave.call("char", ["ab", "c"]) == ["ab", "c"]
    with pytest.raises(TypeError):
        await octave.call("identity", 1j)
    with pytest.raises(EngineError, match="complex results are not supported"):
        await octave.call("sqrt", -1.0)
    assert await octave.call("plus", 1.0, 2.0) == 3.0


async def test_error_in_script_has_the_octave_traceback(octave: OctaveEngine) -> None:
    with pytest.raises(EngineError) as info:
        await octave.call("goalkeeper", np.zeros((3, 2)), np.zeros((2, 2)), -4500.0, 1000.0)
    assert "goalkeeper.m" in info.value.remote_traceback
    assert await octave.call("plus", 2.0, 2.0) == 4.0
    assert octave.health()["errors"] == 1


async def test_printed_output_does_not_corrupt_results(octave: OctaveEngine) -> None:
    assert await octave.call("talk", 1.0) == 2.0
    assert await octave.call("talk", 2.0) == 3.0


async def test_stuck_script_times_out_and_worker_is_replaced(octave: OctaveEngine) -> None:
    t0 = time.monotonic()
    with pytest.raises(EngineTimeout):
        await octave.call("spin", timeout_s=0.3, nargout=0)
    assert time.monotonic() - t0 < 0.3 + 0.3
    assert await octave.call("plus", 1.0, 1.0, timeout_s=30.0) == 2.0
    h = octave.health()
    assert h["timeouts"] == 1 and h["restarts"] == 1


async def test_octave_exit_is_a_dead_worker_and_is_replaced(octave: OctaveEngine) -> None:
    with pytest.raises(EngineWorkerDied, match="exit status 3"):
        await octave.call("die", nargout=0, timeout_s=10.0)
    assert await octave.call("geometry_src.distance", np.array([0.0, 0.0]),
                             np.array([3.0, 4.0]), timeout_s=30.0) == 5.0
    assert octave.health()["crashes"] == 1
