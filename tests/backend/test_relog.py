"""``python -m backend.relog`` (the world model re-run over a log's vision) as a subprocess on
a recorded session (tests/data)."""

import csv
import math
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FIXTURE = ROOT / "tests" / "data" / "fieldsim-2s.log.gz"


def run(module: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", module, *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=120, check=False)


def test_relog_reruns_the_world_model(tmp_path: Path) -> None:
    """The paper's filter over 0.5 s of a simulated session: every object after every merged
    frame, close to the raw detections (``python -m ssllog export``), with velocities."""
    out = tmp_path / "f.csv"
    r = run("backend.relog", str(FIXTURE), "--cache-dir", str(tmp_path / "c"), "--from", "1",
            "--to", "1.5", "--filter", "paper", "--csv", str(out))
    assert r.returncode == 0, r.stderr
    assert r.stderr.endswith(" rows\n")
    raw_out = tmp_path / "r.csv"
    assert run("ssllog", "--cache-dir", str(tmp_path / "c"), "export", str(FIXTURE), "--from",
               "1", "--to", "1.5", "--csv", str(raw_out)).returncode == 0
    rows = list(csv.DictReader(out.open()))
    assert rows and set(rows[0]) == {"t_log_s", "t_capture", "kind", "id", "x_mm", "y_mm",
                                     "orientation_rad", "vx_mm_s", "vy_mm_s", "omega_rad_s",
                                     "visible"}
    assert int(r.stderr.split()[0]) == len(rows)
    assert {r["kind"] for r in rows} == {"ball", "blue", "yellow"}
    times = [float(r["t_log_s"]) for r in rows]
    assert times[0] >= 1.0 and times[-1] <= 1.5 and times == sorted(times)
    raw = {}
    for x in csv.DictReader(raw_out.open()):
        if x["kind"] != "ball":
            raw[(x["kind"], x["id"])] = (float(x["x_mm"]), float(x["y_mm"]))
    last = {(x["kind"], x["id"]): x for x in rows if x["kind"] != "ball"}
    assert len(last) == 12
    for key, x in last.items():
        assert math.dist((float(x["x_mm"]), float(x["y_mm"])), raw[key]) < 60, key


def test_relog_bad_input_is_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.log"
    bad.write_bytes(b"garbage garbage garbage")
    r = run("backend.relog", str(bad), "--cache-dir", str(tmp_path / "c"), "--csv", "-")
    assert r.returncode == 1
    assert r.stderr.startswith("relog: corrupt SSL log at byte 0") and r.stderr.count("\n") == 1
    r = run("backend.relog", str(FIXTURE), "--filter", "nope", "--csv", "-")
    assert r.returncode == 2 and "invalid choice: 'nope'" in r.stderr
