import math

import pytest
from pydantic import BaseModel, ValidationError

from backend.control.params import (
    Algorithm1Params,
    Algorithm2Params,
    ControllerParams,
    ControlSettings,
    HeadingParams,
    LateralParams,
    LimitsParams,
    ProportionalParams,
    RobotOverride,
)

MODELS: list[type[BaseModel]] = [Algorithm1Params, Algorithm2Params, ProportionalParams,
                                 HeadingParams, LateralParams, LimitsParams, RobotOverride]


def test_public_defaults() -> None:
    p = ControllerParams()
    assert (p.algorithm1.v_mps, p.algorithm1.w_mps2, p.algorithm1.k_per_s) == (1.0, 3.0, 3.0)
    assert p.algorithm1.c_smoothing == 0.997
    assert p.algorithm2.a_mps2 == 1.5


@pytest.mark.parametrize("model", MODELS)
def test_every_field_has_default_bounds_description_unit_and_step(model: type[BaseModel]) -> None:
    schema = model.model_json_schema()
    for name, prop in schema["properties"].items():
        if name == "algorithm":  # a choice, not a number
            assert prop.get("description")
            continue
        if "anyOf" in prop:  # Optional overrides
            num = next(p for p in prop["anyOf"] if p.get("type") == "number")
        else:
            num = prop
        assert "default" in prop, name
        assert "minimum" in num and "maximum" in num, name
        assert prop.get("description"), name
        assert "unit" in prop and "step" in prop, name


def test_nan_and_out_of_range_are_rejected() -> None:
    with pytest.raises(ValidationError):
        Algorithm1Params(v_mps=math.nan)
    with pytest.raises(ValidationError):
        Algorithm1Params(k_per_s=-1.0)
    with pytest.raises(ValidationError):
        LimitsParams(max_speed_mps=math.inf)


def test_robot_keys_are_checked() -> None:
    ControlSettings.model_validate({"robots": {"yellow/15": {}}})
    for bad in ("blue/16", "red/1", "blue-3", "blue/"):
        with pytest.raises(ValidationError):
            ControlSettings.model_validate({"robots": {bad: {}}})


def test_overrides_apply_to_every_algorithm() -> None:
    s = ControlSettings.model_validate({"robots": {"blue/1": {"v_mps": 2.0, "w_mps2": 1.0,
                                                              "a_mps2": 0.5}}})
    p = s.params_for("blue", 1)
    assert p.algorithm1.v_mps == p.algorithm2.v_mps == p.proportional.v_mps == 2.0
    assert p.algorithm1.w_mps2 == p.algorithm2.w_mps2 == p.proportional.w_mps2 == 1.0
    assert p.algorithm2.a_mps2 == 0.5
    assert s.params_for("blue", 2) == ControllerParams()
    assert s.algorithm_for("blue", 1) == s.default_algorithm
