"""One input stream's counters (packets, bytes, rate, errors by reason), shared by the relay
and the backend, and the reasons a datagram is refused, named the same everywhere (health,
the Health tab, the logs).

Reasons: ``truncated`` (the protobuf wire format ends inside a field), ``not protobuf`` (not
the wire format at all), ``missing required field`` (parses, but a proto2 ``required`` field
is absent), ``time out of range`` (a capture time far from the receive clock: the world model),
``bad string`` (a string field that is not UTF-8: used with replacement characters),
``oversized`` (larger than the stream's limit), ``no content`` (a wrapper with neither
detection nor geometry), ``backend behind`` (forwarded by the relay, then overwritten on the
backend's bus before its ingest decoded it: a flood faster than the backend decodes),
``other``."""

from __future__ import annotations

from typing import Any

from google.protobuf.message import DecodeError, Message

from sslnet.rate import RateCounter

TRUNCATED = "truncated"
NOT_PROTOBUF = "not protobuf"
MISSING_FIELD = "missing required field"
TIME_OUT_OF_RANGE = "time out of range"
BAD_STRING = "bad string"
OVERSIZED = "oversized"
NO_CONTENT = "no content"
BEHIND = "backend behind"
OTHER = "other"
REASONS = (TRUNCATED, NOT_PROTOBUF, MISSING_FIELD, TIME_OUT_OF_RANGE, BAD_STRING, OVERSIZED,
           NO_CONTENT, BEHIND, OTHER)


class StreamCounter:
    """Packets, bytes, rate, errors (total and by reason) and the last error of one stream."""

    def __init__(self, name: str = "") -> None:
        self.name = name
        self.rate = RateCounter()
        self.bytes = 0
        self.errors = 0
        self.by_reason: dict[str, int] = {}
        self.last_error = ""

    @property
    def packets(self) -> int:
        return self.rate.total

    def packet(self, size: int = 0, now: float | None = None) -> None:
        self.rate.add(now)
        self.bytes += size

    def packets_at(self, n: int, size: int, now: float) -> None:
        """``n`` packets of ``size`` bytes in all, counted at ``now`` (one call per batch)."""
        self.rate.add_many(n, now)
        self.bytes += size

    def error(self, reason: str, detail: str = "", n: int = 1) -> None:
        """Count ``n`` errors of ``reason`` (one of REASONS, or another short name)."""
        self.errors += n
        self.by_reason[reason] = self.by_reason.get(reason, 0) + n
        self.last_error = f"{reason}: {detail}" if detail else reason

    def to_dict(self) -> dict[str, Any]:
        return {
            "packets": self.packets,
            "errors": self.errors,
            "errors_by_reason": dict(sorted(self.by_reason.items())),
            "rate_hz": self.rate.rate_hz(),
            "last_age_s": self.rate.age_s(),
            "last_error": self.last_error,
        }


def wire_problem(data: bytes) -> str:
    """Why ``data`` does not parse as a protobuf message, from its outermost wire format:
    TRUNCATED when it ends inside a field (a datagram cut short), else NOT_PROTOBUF."""
    i, n = 0, len(data)

    def varint() -> int | None:
        nonlocal i
        shift = value = 0
        while i < n:
            b = data[i]
            i += 1
            value |= (b & 0x7F) << shift
            if b < 0x80:
                return value
            shift += 7
            if shift > 63:
                return -1
        return None  # ended inside the varint

    while i < n:
        key = varint()
        if key is None:
            return TRUNCATED
        if key <= 0 or key >> 3 == 0:
            return NOT_PROTOBUF
        wire = key & 7
        if wire == 0:
            v = varint()
            if v is None:
                return TRUNCATED
            if v < 0:
                return NOT_PROTOBUF
        elif wire == 1:
            i += 8
        elif wire == 5:
            i += 4
        elif wire == 2:
            size = varint()
            if size is None:
                return TRUNCATED
            if size < 0:
                return NOT_PROTOBUF
            i += size
        else:  # groups (3, 4) are not used by any SSL message; 6, 7 do not exist
            return NOT_PROTOBUF
        if i > n:
            return TRUNCATED
    return NOT_PROTOBUF  # the outer format is whole: something inside is wrong


def parse_message(msg: Message, data: bytes) -> tuple[str, str] | None:
    """Parses ``data`` into ``msg``. On failure (reason, detail): the reason one of this
    module's (TRUNCATED / NOT_PROTOBUF from ``wire_problem``, MISSING_FIELD for a proto2
    message without a required field), the detail the parser's words or the missing fields
    (at most five). The one protobuf parse with a reason of the relay, the backend and fieldsim."""
    try:
        msg.ParseFromString(data)
    except (DecodeError, RuntimeError, ValueError) as exc:
        return wire_problem(data), str(exc)
    if not msg.IsInitialized():
        errors: list[str] = msg.FindInitializationErrors()  # type: ignore[attr-defined]
        return MISSING_FIELD, ", ".join(errors[:5])
    return None
