"""The test harness itself: a test that would hang fails (pytest-timeout), and a skipped Octave
or multicast suite is said at the end and fails the run under CI (tests/conftest.py)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _pytest(tmp: Path, body: str, *args: str, ci: bool = False) -> subprocess.CompletedProcess[str]:
    f = tmp / "test_sample.py"
    f.write_text(body)
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    if ci:
        env["CI"] = "true"
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "tests.conftest",
         "--rootdir", str(ROOT), "-c", str(ROOT / "pyproject.toml"), *args, str(f)],
        cwd=ROOT, capture_output=True, text=True, timeout=120, env=env, check=False)


def test_a_test_that_would_hang_fails_with_the_timeout(tmp_path: Path) -> None:
    r = _pytest(tmp_path, "import time\n\ndef test_hangs():\n    time.sleep(600)\n",
                "--timeout", "2")
    assert r.returncode == 1, r.stdout
    assert "Timeout" in r.stdout


_SKIPPED = '''import pytest

@pytest.mark.skipif(True, reason="GNU Octave (octave-cli) is not installed")
def test_engine():
    pass
'''


def test_a_skipped_octave_suite_is_said_and_fails_under_ci(tmp_path: Path) -> None:
    local = _pytest(tmp_path, _SKIPPED)
    assert local.returncode == 0
    assert "SUITES THAT DID NOT RUN" in local.stdout
    assert "1 test(s) did not run: GNU Octave" in local.stdout
    ci = _pytest(tmp_path, _SKIPPED, ci=True)
    assert ci.returncode == 1, ci.stdout
    assert "was skipped under CI" in ci.stdout
