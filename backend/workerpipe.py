"""The worker side of the pipe protocol of the compute engine's numpy workers
(``backend/engine/_numpy_worker.py``) and the team-code workers (``backend/teamcode/worker.py``):
frames of a 4-byte big-endian length and a pickle on standard input and output. Imports
nothing of the station: a worker's start-up time is the time it takes to import."""

from __future__ import annotations

import os
import pickle
import struct
import sys
from typing import Any, BinaryIO


def take_stdio() -> tuple[BinaryIO, BinaryIO]:
    """The protocol's input and output. Standard output (fd 1) is pointed at standard error
    after its descriptor was taken for the protocol: ``print`` and C-level writes of the
    code the worker runs go to the log and cannot corrupt a frame."""
    proto_out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    return sys.stdin.buffer, proto_out


def _read_exact(f: BinaryIO, n: int) -> bytes | None:
    buf = b""
    while len(buf) < n:
        chunk = f.read(n - len(buf))
        if not chunk:
            return None
        buf += chunk
    return buf


def read_frame(f: BinaryIO) -> bytes | None:
    """The next frame's pickle, or None at the end of the input (the station closed it)."""
    head = _read_exact(f, 4)
    if head is None:
        return None
    (n,) = struct.unpack(">I", head)
    return _read_exact(f, n)


def send(out: BinaryIO, obj: Any) -> None:
    """One frame (pickle's errors are the caller's: the reply it sends instead differs)."""
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    out.write(struct.pack(">I", len(data)) + data)
    out.flush()
