"""The protobuf wire format's two building blocks, written by hand: the varint and a field's
key. For bytes the generated classes do not make: the tracked-vision packet of every world
tick (backend/world/tracked.py: the generated classes cost too much there), the fuzzer's
malformed datagrams (scripts/fuzz_station.py) and the tests' messages built from the official
field numbers (tests/wire.py)."""

from __future__ import annotations


def varint(n: int) -> bytes:
    """``n`` (>= 0) as a base-128 varint, least significant group first."""
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def key(field: int, wire: int) -> bytes:
    """A field's key: its number and wire type (0 varint, 1 64-bit, 2 length-delimited,
    5 32-bit)."""
    return varint(field << 3 | wire)
