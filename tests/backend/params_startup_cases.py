"""Bad contents of the state folder, shared by the unit and the real-process tests."""

from __future__ import annotations

import json
from pathlib import Path

# (name, what params.json holds: bytes, or None for a folder in its place)
BAD_FILES: list[tuple[str, bytes | None]] = [
    ("a JSON array", b"[]"),
    ("a JSON string", b'"values"'),
    ("not JSON", b"{\"values\": {"),
    ("invalid UTF-8", b'{"values": {"team": {"our_team": "\xff\xfe"}}}'),
    ("values not an object", b'{"version": 3, "values": [1, 2]}'),
    ("a bad version", json.dumps({"version": "seven",
                                  "values": {"safety": {"stop_speed_mps": 0.5}}}).encode()),
    ("a negative version", json.dumps({"version": -1, "values": {}}).encode()),
    ("wrong field types", json.dumps({"version": 2, "values": {
        "safety": {"stop_speed_mps": "fast"}}}).encode()),
    ("a newer schema", json.dumps({"schema": 99, "version": 4, "values": {
        "safety": {"stop_speed_mps": 0.5}}}).encode()),
    ("deep nesting", b"[" * 100_000 + b"]" * 100_000),
    ("a folder in its place", None),
]


def write_bad(state_dir: Path, content: bytes | None) -> Path:
    state_dir.mkdir(parents=True, exist_ok=True)
    f = state_dir / "params.json"
    if content is None:
        f.mkdir()
        (f / "junk").write_text("x")
    else:
        f.write_bytes(content)
    return f
