"""The generated TypeScript types and the message reference of docs/api.md are what
scripts/gen_contract.py makes of backend/contract.py today (regenerate: make contract)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_generated_files_are_up_to_date() -> None:
    r = subprocess.run([sys.executable, "scripts/gen_contract.py", "--check"], cwd=ROOT,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr


def test_the_typescript_names_every_message() -> None:
    ts = (ROOT / "frontend/src/api/contract.gen.ts").read_text(encoding="utf-8")
    assert 'export type TargetSource = "operator" | "strategy" | "team";' in ts
    for name in ("World", "Health", "Geometry", "SnapshotMessage", "WorldMessage",
                 "HealthMessage", "GeometryMessage", "ParamsMessage"):
        assert f"export interface {name} {{" in ts, name
