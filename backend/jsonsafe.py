"""JSON out of the station that always encodes: the last line of defence behind the decoders.

Strings and numbers from the wire are cleaned where they are decoded (``wire_str``, the
geometry and detection decoders). Should something get past them (a decoder that forgets, a
value a processor computes), the world, health, referee and geometry must still reach the
page: one bad value never answers 500 nor closes a websocket.

``dumps`` tries the strict encoding first (no NaN, valid UTF-8): orjson where it is installed
(a world message of 11 v 11 in ~25 us instead of ~400-600 us: the station writes one per
websocket publication, 60 a second, on its own thread), which writes NaN/inf as null, then the
standard encoder for what orjson refuses (integers beyond 64 bits, keys that are not text,
nesting deeper than 254, lone surrogates, types it does not know); only when that fails too does
it walk the value and repair it: NaN/inf -> null, bytes -> text decoded with replacement
characters, lone surrogates -> U+FFFD, tuples and sets -> lists, non-string keys -> text,
anything else (and anything nested deeper than ``MAX_DEPTH``, a cycle) -> null. A repair other
than a non-finite number is logged once per kind of message (rate-limited) with where it was,
and counted in ``repairs``."""

from __future__ import annotations

import importlib
import json
import logging
import math
import re
from collections.abc import Mapping
from numbers import Integral, Real
from typing import Any

from starlette.background import BackgroundTask
from starlette.responses import JSONResponse

from sslnet.ratelog import RateLimitedLog

log = logging.getLogger("touchline.json")
_ratelog = RateLimitedLog(log, interval_s=10.0)


def _orjson() -> Any:
    """The orjson module, or None where it is not installed (the standard encoder alone: the
    same JSON, slower; a venv made before it became a dependency)."""
    try:
        return importlib.import_module("orjson")
    except ImportError:  # pragma: no cover
        return None


orjson: Any = _orjson()

#: numpy numbers as numbers (the standard encoder writes a numpy float64 as a float, the repair
#: other numpy numbers; a numpy bool, which it made null, is a boolean here); dataclasses and
#: datetimes are refused as the standard encoder refuses them (then repaired)
_ORJSON_OPTIONS = 0 if orjson is None else (
    orjson.OPT_SERIALIZE_NUMPY | orjson.OPT_PASSTHROUGH_DATACLASS
    | orjson.OPT_PASSTHROUGH_DATETIME)

MAX_DEPTH = 64
_SURROGATE = re.compile("[\ud800-\udfff]")

#: repaired messages by kind ("world", "health", ...); for tests and for the curious
repairs: dict[str, int] = {}


def dumps(obj: Any, what: str = "json") -> str:
    """``obj`` as compact JSON text that is strict (no NaN) and encodes as UTF-8."""
    if orjson is not None:
        try:
            encoded: bytes = orjson.dumps(obj, option=_ORJSON_OPTIONS)
            return encoded.decode("utf-8")
        except (TypeError, ValueError, RecursionError):  # orjson.JSONEncodeError is a TypeError
            pass
    try:
        text = json.dumps(obj, ensure_ascii=False, allow_nan=False, separators=(",", ":"))
        text.encode("utf-8")  # lone surrogates would fail later, in the socket or response
        return text
    except (TypeError, ValueError, RecursionError):  # UnicodeEncodeError is a ValueError
        pass
    problems: list[str] = []
    text = json.dumps(_repair(obj, "$", 0, problems), ensure_ascii=False, allow_nan=False,
                      separators=(",", ":"))
    if problems:
        repairs[what] = repairs.get(what, 0) + 1
        _ratelog.warning(f"json-{what}", "%s message: %d value(s) could not be JSON and were "
                         "replaced (%s)", what, len(problems), "; ".join(problems[:5]))
    return text


def dumps_bytes(obj: Any, what: str = "json") -> bytes:
    return dumps(obj, what).encode("utf-8")


def _text(s: str) -> str:
    return _SURROGATE.sub("\ufffd", s)


def _repair(obj: Any, path: str, depth: int, problems: list[str]) -> Any:
    if obj is None or isinstance(obj, bool):
        return obj
    if isinstance(obj, str):
        try:
            obj.encode("utf-8")
            return obj
        except UnicodeEncodeError:
            problems.append(f"{path}: text that is not UTF-8")
            return _text(obj)
    if isinstance(obj, Integral):
        i = int(obj)
        if i.bit_length() > 1000:  # Python refuses to print ints of more than 4300 digits
            problems.append(f"{path}: an integer of {i.bit_length()} bits")
            return None
        return i
    if isinstance(obj, Real):
        f = float(obj)
        return f if math.isfinite(f) else None  # the documented NaN/inf -> null: no log
    if isinstance(obj, bytes | bytearray | memoryview):
        problems.append(f"{path}: bytes")
        return bytes(obj).decode("utf-8", "replace")
    if depth >= MAX_DEPTH:
        problems.append(f"{path}: nested deeper than {MAX_DEPTH} (or a cycle)")
        return None
    if isinstance(obj, Mapping):
        out: dict[str, Any] = {}
        for k, v in obj.items():
            key = _key(k, path, problems)
            out[key] = _repair(v, f"{path}.{key}", depth + 1, problems)
        return out
    if isinstance(obj, list | tuple | set | frozenset):
        return [_repair(v, f"{path}[{i}]", depth + 1, problems) for i, v in enumerate(obj)]
    problems.append(f"{path}: a {type(obj).__name__}")
    return None


def _key(k: Any, path: str, problems: list[str]) -> str:
    if isinstance(k, str):
        return _repair(k, f"{path} key", 0, problems)  # type: ignore[no-any-return]
    if k is None or isinstance(k, bool | int | float):
        return json.dumps(k) if k is None or isinstance(k, bool) else str(k)
    if isinstance(k, bytes):
        problems.append(f"{path}: a bytes key")
        return k.decode("utf-8", "replace")
    problems.append(f"{path}: a {type(k).__name__} key")
    return _text(str(k))


class SafeJSONResponse(JSONResponse):
    """A JSON response that never fails to render (see ``dumps``); ``what`` names it in the
    log should it need a repair."""

    def __init__(self, content: Any, status_code: int = 200,
                 headers: Mapping[str, str] | None = None, media_type: str | None = None,
                 background: BackgroundTask | None = None, *, what: str = "http") -> None:
        self.what = what
        super().__init__(content, status_code, headers, media_type, background)

    def render(self, content: Any) -> bytes:
        return dumps_bytes(content, getattr(self, "what", "http"))
