"""A tiny protobuf wire writer and reader for tests: bytes built by hand from the official
field numbers, so wire compatibility is checked against the protocol, not only against our
own generated code. The varint and the key are sslnet.wire's (the tracked-vision encoder's
too)."""

from __future__ import annotations

import struct

from sslnet.wire import key, varint

__all__ = ["f32", "f64", "key", "ld", "read_fields", "uv", "varint"]


def uv(field: int, v: int) -> bytes:
    """A varint field (wire type 0)."""
    return key(field, 0) + varint(v)


def f32(field: int, v: float) -> bytes:
    """A float field (wire type 5, little-endian)."""
    return key(field, 5) + struct.pack("<f", v)


def f64(field: int, v: float) -> bytes:
    """A double field (wire type 1, little-endian)."""
    return key(field, 1) + struct.pack("<d", v)


def ld(field: int, body: bytes) -> bytes:
    """A length-delimited field (wire type 2): submessage, string or bytes."""
    return key(field, 2) + varint(len(body)) + body


def read_fields(buf: bytes) -> list[tuple[int, int, object]]:
    """(field, wire type, value) for each field; raw bytes for wire types 1, 2 and 5."""
    out: list[tuple[int, int, object]] = []
    i = 0

    def read_varint() -> int:
        nonlocal i
        shift = result = 0
        while True:
            b = buf[i]
            i += 1
            result |= (b & 0x7F) << shift
            shift += 7
            if not b & 0x80:
                return result

    while i < len(buf):
        k = read_varint()
        field, wire = k >> 3, k & 7
        value: object
        if wire == 0:
            value = read_varint()
        elif wire == 1:
            value = buf[i:i + 8]
            i += 8
        elif wire == 2:
            n = read_varint()
            value = buf[i:i + n]
            i += n
        elif wire == 5:
            value = buf[i:i + 4]
            i += 4
        else:
            raise ValueError(f"unsupported wire type {wire}")
        out.append((field, wire, value))
    return out
