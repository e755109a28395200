"""The real backend process starts whatever its state folder holds: the defect was a
params.json holding [] that raised at start-up (the launcher gave up after 5 crashes), and a
file with a bad version set aside while its values stayed in use."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from backend.params.model import StationParams
from launcher.supervisor import free_tcp_port
from tests.backend.params_startup_cases import BAD_FILES, write_bad

from .conftest import ROOT, stop_process

CASES = [c for c in BAD_FILES if c[0] in ("a JSON array", "a bad version",
                                          "a folder in its place")]


@pytest.mark.parametrize("name,content", CASES, ids=[n for n, _ in CASES])
def test_the_backend_starts_with_a_bad_params_file(tmp_path: Path, name: str,
                                                   content: bytes | None) -> None:
    write_bad(tmp_path, content)
    port = free_tcp_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "backend", "--port", str(port), "--state-dir", str(tmp_path),
         "--relay-pub", f"tcp://127.0.0.1:{free_tcp_port()}", "--relay-sub", f"tcp://127.0.0.1:{free_tcp_port()}"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        health = None
        while health is None:
            assert proc.poll() is None, "the backend exited:\n" + (
                proc.stdout.read() if proc.stdout else "")
            assert time.monotonic() < deadline, "the backend did not answer in 60 s"
            try:
                health = httpx.get(url + "/api/health", timeout=2).json()
            except httpx.HTTPError:
                time.sleep(0.2)
        warning = [w for w in health["warnings"] if "params.json was not usable" in w]
        assert len(warning) == 1 and "default parameters in use" in warning[0], health["warnings"]
        # the values in use are the ones the log and the warning say: the defaults
        assert httpx.get(url + "/api/params", timeout=5).json()["values"] == \
            StationParams().model_dump(mode="json")
        assert len(list(tmp_path.glob("params.invalid-*.json"))) == 1
    finally:
        stop_process(proc, 15)
    log = proc.stdout.read() if proc.stdout else ""
    assert "default parameters in use" in log
