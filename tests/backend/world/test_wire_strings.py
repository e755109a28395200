"""Every string the decoders take from the wire is valid UTF-8 when it leaves them, whichever
field it is: each message is filled by reflection (every field, every game event kind), each
string is made invalid UTF-8 in the datagram, and what the decoders give the station must be
strict JSON with each of those strings decoded with replacement and named as bad."""

from __future__ import annotations

import json
from dataclasses import asdict
from typing import Any

from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from backend.world.decode import decode_detection, geometry_to_dict
from backend.world.referee import decode_referee
from sslpb.ssl_gc_referee_message_pb2 import Referee
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

MARK = "Zq9!"  # 4 bytes, replaced by 4 bytes that are not UTF-8 (lengths stay valid)
BAD = b"\xff\xfeZ\xc3"


def _fill(msg: Message, depth: int = 0) -> None:
    """Sets every field of ``msg`` (one of each oneof), strings to MARK."""
    for f in msg.DESCRIPTOR.fields:
        oneof = f.containing_oneof
        if oneof is not None and msg.WhichOneof(oneof.name) is not None:
            continue
        repeated = f.is_repeated
        if f.type == FieldDescriptor.TYPE_MESSAGE:
            if depth >= 5:
                continue
            _fill(getattr(msg, f.name).add() if repeated else getattr(msg, f.name), depth + 1)
            continue
        value: Any
        if f.type == FieldDescriptor.TYPE_STRING:
            value = MARK
        elif f.type == FieldDescriptor.TYPE_BYTES:
            value = b"\x00"
        elif f.type == FieldDescriptor.TYPE_BOOL:
            value = True
        elif f.type == FieldDescriptor.TYPE_ENUM:
            value = f.enum_type.values[0].number
        elif f.cpp_type in (FieldDescriptor.CPPTYPE_FLOAT, FieldDescriptor.CPPTYPE_DOUBLE):
            value = 1.0
        else:
            value = 1
        if repeated:
            getattr(msg, f.name).append(value)
        else:
            setattr(msg, f.name, value)


def _corrupt(msg: Message) -> bytes:
    data = msg.SerializeToString()
    assert MARK.encode() in data
    return data.replace(MARK.encode(), BAD)


def _strings(obj: Any) -> list[str]:
    if isinstance(obj, str):
        return [obj]
    if isinstance(obj, dict):
        return [s for k, v in obj.items() for s in (*_strings(k), *_strings(v))]
    if isinstance(obj, list | tuple):
        return [s for v in obj for s in _strings(v)]
    assert not isinstance(obj, bytes | bytearray), obj
    return []


def _strict_json(obj: Any) -> str:
    text = json.dumps(obj, ensure_ascii=False, allow_nan=False)
    text.encode("utf-8")  # no lone surrogates
    return text


def test_every_referee_string_is_decoded_with_replacement_and_named() -> None:
    ref = Referee()
    _fill(ref)
    # one game event of every kind, so a text field of any of them is covered
    template = ref.game_events[0]
    del ref.game_events[:]
    for kind in template.DESCRIPTOR.oneofs_by_name["event"].fields:
        ev = ref.game_events.add()
        _fill(getattr(ev, kind.name), 1)
        _fill(ev, 1)
    parsed = Referee.FromString(_corrupt(ref))
    assert isinstance(parsed.blue.name, bytes)  # what upb hands over for a bad proto2 string
    bad: list[str] = []
    out = decode_referee(parsed, bad).to_dict(0.0)
    _strict_json(out)
    texts = _strings(out)
    assert not any(MARK in s or "Zq9" in s for s in texts)
    damaged = [s for s in texts if "\ufffd" in s]
    # team names, source id, status message, and per event its id and origin
    assert len(damaged) >= 4 and len(damaged) == len(bad), (damaged, bad)
    assert {"blue team name", "yellow team name", "source identifier",
            "status message"} <= set(bad)


def test_every_geometry_and_detection_string_is_decoded_with_replacement_and_named() -> None:
    pkt = SSL_WrapperPacket()
    _fill(pkt)
    parsed = SSL_WrapperPacket.FromString(_corrupt(pkt))
    bad: list[str] = []
    geo = geometry_to_dict(parsed.geometry, bad)
    _strict_json(geo)
    names = [x["name"] for x in (*geo["lines"], *geo["arcs"])]
    assert names and all("\ufffd" in n for n in names)
    assert sorted(bad) == sorted(["field line name"] * len(geo["lines"])
                                 + ["field arc name"] * len(geo["arcs"]))
    frame = asdict(decode_detection(parsed.detection, 1))
    assert not any("Zq9" in s for s in _strings(frame))
    _strict_json(frame)
