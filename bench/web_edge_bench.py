"""Web edge cost (not a test): milliseconds to scan a 1 MiB body for its JSON depth (the
guard runs it on every state-changing request, holding the GIL), for shapes that once were
slow, and to encode a world message through backend.jsonsafe (clean: the strict fast path;
with one bad value: the repairing walk).

Usage: .venv/bin/python bench/web_edge_bench.py
"""

from __future__ import annotations

import json
import logging
import sys
import timeit
from functools import partial
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.jsonsafe import dumps
from backend.security import MAX_BODY_BYTES, json_depth

MIB = MAX_BODY_BYTES


def bodies() -> dict[str, bytes]:
    return {
        'escaped quotes "\\"\\"...': (b'"' + b'\\"' * MIB)[:MIB],
        "open brackets [[[...": b"[" * MIB,
        "pairs [][]...": b"[]" * (MIB // 2),
        'quotes """...': b'"' * MIB,
        "an open string": b'"' + b"a" * (MIB - 1),
        "a real JSON body": json.dumps({"values": {f"k{i}": [i, {"s": "x]["}] for i in
                                                  range(30000)}}).encode()[:MIB],
    }


def world(robots: int = 22, bad: bool = False) -> dict[str, object]:
    return {"type": "world", "world": {
        "robots": [{"team": "blue", "id": i, "x": 1.5 * i, "y": -2.0, "orientation": 0.1,
                    "cameras": [0, 1], "target": None, "command": {"forward_mps": 0.5}}
                   for i in range(robots)],
        "referee": {"blue": {"name": b"\xff" if bad else "ER-Force"}, "yellow": {"name": "TIGERs"}},
    }}


def main() -> None:
    logging.getLogger("touchline.json").setLevel(logging.ERROR)  # the repair is on purpose
    for name, body in bodies().items():
        n = 5
        t = timeit.timeit(partial(json_depth, body), number=n) / n
        print(f"json_depth  {name:28s} {len(body) / MIB:4.1f} MiB  {t * 1e3:8.2f} ms")
    for label, w in (("clean world", world()), ("world with a bad value", world(bad=True))):
        n = 2000
        t = timeit.timeit(partial(dumps, w, "bench"), number=n) / n
        print(f"dumps       {label:28s}           {t * 1e6:8.1f} us")


if __name__ == "__main__":
    main()
