"""Any Data Bus value as plain data for a team processor's ``inputs`` (dicts, lists, numbers,
strings, booleans, None): dataclasses and named tuples become dicts, tuple keys
("blue", 3) become "blue/3", protobuf messages their JSON form, enums their value. Generic,
so a processor can read every topic, and bounded (depth, items) so no topic costs much."""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from typing import Any

from google.protobuf.json_format import MessageToDict
from google.protobuf.message import Message

MAX_DEPTH = 8
MAX_ITEMS = 2000


def _key(k: Any) -> str:
    if isinstance(k, tuple):
        return "/".join(str(x) for x in k)
    return str(k)


def plain(v: Any, depth: int = 0) -> Any:
    if v is None or isinstance(v, bool | int | float | str):
        return v
    if depth >= MAX_DEPTH:
        return None
    if isinstance(v, enum.Enum):
        return plain(v.value, depth + 1)
    if isinstance(v, bytes | bytearray | memoryview):
        return {"bytes": len(v)}  # raw datagrams: their size, not their content
    if isinstance(v, Message):
        return MessageToDict(v, preserving_proto_field_name=True)
    if dataclasses.is_dataclass(v) and not isinstance(v, type):
        return {f.name: plain(getattr(v, f.name), depth + 1) for f in dataclasses.fields(v)
                if f.repr}
    if isinstance(v, tuple) and hasattr(v, "_fields"):
        return {name: plain(x, depth + 1) for name, x in zip(v._fields, v, strict=False)}
    if isinstance(v, Mapping):
        return {_key(k): plain(x, depth + 1)
                for k, x in list(v.items())[:MAX_ITEMS]}
    if isinstance(v, list | tuple | set | frozenset):
        return [plain(x, depth + 1) for x in list(v)[:MAX_ITEMS]]
    return str(v)[:200]
