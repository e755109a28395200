"""The real-process fuzz target, short: ``scripts/fuzz_station.py --count 20000`` starts the
station through the launcher, sends 20 000 malformed vision and referee datagrams on loopback
multicast, and exits non-zero if a process died or restarted, the loop fell under its rate
floor, the world stopped following the simulator, or the counts by reason do not account for
what was sent (``make fuzz`` runs it with 10^6)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from sslnet.multicast import loopback_multicast_ok

ROOT = Path(__file__).resolve().parents[2]


def test_station_survives_20000_malformed_datagrams(tmp_path: Path) -> None:
    if not loopback_multicast_ok():
        pytest.skip("loopback multicast is not set up (make multicast)")
    out = tmp_path / "fuzz.json"
    run = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "fuzz_station.py"), "--count", "20000",
         "--rate", "4000", "--check-every", "2", "--settle", "2", "--json", str(out)],
        cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout[-6000:] + run.stderr[-3000:]
    report = json.loads(out.read_text())
    assert report["sent"] == 20000
    for stream in ("vision", "referee"):
        s = report["streams"][stream]
        assert s["sent"] > 0
        # the relay's own reasons are never lost after the kernel: empty and oversized
        assert s["reasons"]["relay.no content"]["counted"] >= \
            s["reasons"]["relay.no content"]["expected"] - s["kernel_drops"]
