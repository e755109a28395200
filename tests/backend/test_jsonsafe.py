"""backend.jsonsafe: whatever value reaches the JSON encoder, the text comes out strict (no
NaN) and valid UTF-8; clean values come out exactly as json would write them; a repair is
logged once per kind of message (rate-limited)."""

from __future__ import annotations

import json
import logging
import math
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from backend import jsonsafe
from backend.jsonsafe import SafeJSONResponse, dumps


def _strict(text: str) -> Any:
    text.encode("utf-8")  # raises on a lone surrogate
    return json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))


class _Thing:
    pass


# every kind of value a processor or a decoder could hand over, clean or not
_any_text = st.text(alphabet=st.characters(exclude_categories=()), max_size=8)
_leaf = (st.none() | st.booleans() | st.integers() | st.integers(-(10 ** 400), 10 ** 400)
         | st.floats(allow_nan=True, allow_infinity=True) | _any_text | st.binary(max_size=8)
         | st.builds(_Thing))
_key = _any_text | st.integers() | st.booleans() | st.none() | st.binary(max_size=4) \
    | st.floats(allow_nan=False)
_value = st.recursive(
    _leaf,
    lambda kids: (st.lists(kids, max_size=4) | st.lists(kids, max_size=3).map(tuple)
                  | st.dictionaries(_key, kids, max_size=4)),
    max_leaves=25)


@given(_value)
def test_anything_becomes_strict_utf8_json(value: Any) -> None:
    _strict(dumps(value, "test"))


_clean = st.recursive(
    st.none() | st.booleans() | st.integers(-(2 ** 63), 2 ** 63)
    | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=8),
    lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.text(max_size=6), kids,
                                                             max_size=4),
    max_leaves=25)


@given(_clean)
def test_a_clean_value_is_written_as_json_writes_it(value: Any) -> None:
    assert json.loads(dumps(value)) == json.loads(json.dumps(value))


def test_what_each_repair_gives() -> None:
    nested: list[Any] = []
    cycle: dict[str, Any] = {"self": None}
    cycle["self"] = cycle
    out = _strict(dumps({
        "nan": math.nan, "inf": [math.inf, -math.inf], "bytes": b"ab\xffc",
        "surrogate": "x\udcffy", "tuple": (1, 2), "set": {3}, "thing": _Thing(),
        b"key\xff": 1, 7: "seven", None: 0, "cycle": cycle, "deep": nested,
        "big": 10 ** 5000,
    }))
    assert out["nan"] is None and out["inf"] == [None, None]
    assert out["bytes"] == "ab\ufffdc" and out["surrogate"] == "x\ufffdy"
    assert out["tuple"] == [1, 2] and out["set"] == [3] and out["thing"] is None
    assert out["key\ufffd"] == 1 and out["7"] == "seven" and out["null"] == 0
    assert out["big"] is None
    # a cycle is cut where it exceeds the depth bound, not followed forever
    depth, node = 0, out["cycle"]
    while isinstance(node, dict):
        depth, node = depth + 1, node["self"]
    assert node is None and depth <= jsonsafe.MAX_DEPTH


def test_a_repair_is_logged_once_per_kind_and_counted(caplog: pytest.LogCaptureFixture) -> None:
    before = jsonsafe.repairs.get("unit-test", 0)
    with caplog.at_level(logging.WARNING, logger="touchline.json"):
        for _ in range(5):
            dumps({"team": {"name": b"\xff"}}, "unit-test")
        dumps({"x": math.nan}, "unit-test-nan")  # NaN -> null is the rule, not a repair
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "unit-test message" in lines[0] and "$.team.name" in lines[0]
    assert jsonsafe.repairs["unit-test"] == before + 5
    assert "unit-test-nan" not in jsonsafe.repairs


def test_the_response_renders_whatever_it_carries() -> None:
    r = SafeJSONResponse({"name": b"\xfe", "x": math.nan}, status_code=201, what="unit-test")
    assert r.status_code == 201 and r.media_type == "application/json"
    assert _strict(r.body.decode("utf-8")) == {"name": "\ufffd", "x": None}


@given(_value)
def test_orjson_and_the_standard_encoder_give_the_same_json(value: Any) -> None:
    """orjson (where installed) writes what the standard encoder writes, repairs included:
    what it refuses goes the standard way."""
    pytest.importorskip("orjson")
    fast = dumps(value, "test")
    saved = jsonsafe.orjson
    jsonsafe.orjson = None
    try:
        standard = dumps(value, "test")
    finally:
        jsonsafe.orjson = saved
    assert _strict(fast) == _strict(standard)


def test_numpy_numbers_are_numbers() -> None:
    import numpy as np
    out = _strict(dumps({"f64": np.float64(1.5), "nan64": np.float64("nan"),
                         "i64": np.int64(-3), "f32": np.float32(0.5)}))
    assert out == {"f64": 1.5, "nan64": None, "i64": -3, "f32": 0.5}
