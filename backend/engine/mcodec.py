"""The binary value format between the OctaveEngine and its Octave workers.

Little-endian; a value is a one-byte tag and a payload:

====  ==================================================  ===============================
tag   payload                                             Python <-> Octave
====  ==================================================  ===============================
n     (none)                                              None -> [] (Octave never sends n)
d     u32 ndims, u32 dims..., float64 data column-major   double matrix
l     u32 ndims, u32 dims..., u8 data column-major        logical matrix
s     u32 byte count, bytes (UTF-8)                       char row vector
c     u32 ndims, u32 dims..., values column-major         cell array
r     u32 field count, (s name, value)...                 scalar struct
====  ==================================================  ===============================

Python to Octave: None -> []; bool / numpy bool arrays -> logical; int, float, numpy real
arrays (any integer or float dtype) -> double, a 0-d array or number as 1x1 and a 1-D
array of n as a 1 x n row (points [x y] are rows, as in the team's scripts), 2-D and more
keep their shape; str -> char row; list / tuple -> 1 x n cell; numpy object arrays -> cell
of that shape; dict with str keys -> scalar struct. Anything else (complex, bytes, sets,
objects) raises TypeError before the call.

Octave to Python: a 1x1 double -> float, a 1x1 logical -> bool, other double/logical
arrays -> numpy arrays of Octave's shape (always 2-D or more: a row [x y] is shape (1, 2));
integer and single classes -> float64 (converted by Octave); char row -> str, a char matrix
-> list of str (its rows, trailing blanks removed); cell 1xn / nx1 / 0x0 -> list, other cell
shapes -> nested lists (rows); scalar struct -> dict. Complex values, struct arrays,
function handles and objects are errors of the call.
"""

from __future__ import annotations

import struct
from typing import Any

import numpy as np

_U32 = struct.Struct("<I")


def _dims(shape: tuple[int, ...]) -> bytes:
    return _U32.pack(len(shape)) + struct.pack(f"<{len(shape)}I", *shape)


def encode(value: Any) -> bytes:
    out: list[bytes] = []
    _enc(value, out)
    return b"".join(out)


def _matlab_shape(a: np.ndarray[Any, Any]) -> tuple[int, ...]:
    if a.ndim == 0:
        return (1, 1)
    if a.ndim == 1:
        return (1, a.shape[0])
    return tuple(int(x) for x in a.shape)


def _enc(v: Any, out: list[bytes]) -> None:
    if v is None:
        out.append(b"n")
    elif isinstance(v, bool | np.bool_):
        out.append(b"l" + _dims((1, 1)) + (b"\x01" if v else b"\x00"))
    elif isinstance(v, int | float | np.integer | np.floating):
        out.append(b"d" + _dims((1, 1)) + struct.pack("<d", float(v)))
    elif isinstance(v, str):
        raw = v.encode("utf-8")
        out.append(b"s" + _U32.pack(len(raw)) + raw)
    elif isinstance(v, np.ndarray):
        shape = _matlab_shape(v)
        if v.dtype == np.bool_:
            out.append(b"l" + _dims(shape)
                       + np.asarray(v, dtype=np.uint8).reshape(shape).tobytes(order="F"))
        elif v.dtype.kind in "iuf":
            out.append(b"d" + _dims(shape)
                       + np.asarray(v, dtype="<f8").reshape(shape).tobytes(order="F"))
        elif v.dtype == object:
            out.append(b"c" + _dims(shape))
            for item in v.reshape(shape).ravel(order="F"):
                _enc(item, out)
        else:
            raise TypeError(f"unsupported numpy dtype {v.dtype} for Octave")
    elif isinstance(v, list | tuple):
        out.append(b"c" + _dims((1, len(v))))
        for item in v:
            _enc(item, out)
    elif isinstance(v, dict):
        out.append(b"r" + _U32.pack(len(v)))
        for key, item in v.items():
            if not isinstance(key, str) or not key.isidentifier():
                raise TypeError(f"struct field names must be identifiers, got {key!r}")
            _enc(key, out)
            _enc(item, out)
    else:
        raise TypeError(f"cannot pass a {type(v).__name__} to Octave")


class _Reader:
    def __init__(self, data: bytes) -> None:
        self.data = memoryview(data)
        self.pos = 0

    def take(self, n: int) -> memoryview:
        if self.pos + n > len(self.data):
            raise ValueError("truncated Octave value")
        chunk = self.data[self.pos:self.pos + n]
        self.pos += n
        return chunk

    def u32(self) -> int:
        return int(_U32.unpack(self.take(4))[0])

    def dims(self) -> tuple[int, ...]:
        nd = self.u32()
        return tuple(struct.unpack(f"<{nd}I", self.take(4 * nd)))


def decode(data: bytes) -> Any:
    r = _Reader(data)
    v = _dec(r)
    if r.pos != len(r.data):
        raise ValueError("trailing bytes after Octave value")
    return v


def decode_many(data: bytes) -> list[Any]:
    r = _Reader(data)
    out = []
    while r.pos < len(r.data):
        out.append(_dec(r))
    return out


def _dec(r: _Reader) -> Any:
    tag = bytes(r.take(1))
    if tag == b"n":
        return None
    if tag in (b"d", b"l"):
        shape = r.dims()
        n = int(np.prod(shape))
        if tag == b"d":
            arr = np.frombuffer(r.take(8 * n), dtype="<f8").astype(np.float64)
        else:
            arr = np.frombuffer(r.take(n), dtype=np.uint8).astype(np.bool_)
        if n == 1 and all(d == 1 for d in shape):
            return bool(arr[0]) if tag == b"l" else float(arr[0])
        return np.ascontiguousarray(arr.reshape(shape, order="F"))
    if tag == b"s":
        return bytes(r.take(r.u32())).decode("utf-8", errors="replace")
    if tag == b"c":
        shape = r.dims()
        n = int(np.prod(shape))
        items = [_dec(r) for _ in range(n)]
        if len(shape) == 2 and (shape[0] <= 1 or shape[1] <= 1):
            return items
        cells = np.empty(n, dtype=object)
        cells[:] = items
        nested: Any = cells.reshape(shape, order="F").tolist()
        return nested
    if tag == b"r":
        n = r.u32()
        out: dict[str, Any] = {}
        for _ in range(n):
            key = _dec(r)
            out[str(key)] = _dec(r)
        return out
    raise ValueError(f"bad Octave value tag {tag!r}")
