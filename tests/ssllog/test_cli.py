"""``python -m ssllog`` run as a subprocess on a small hand-built log."""

import csv
import subprocess
import sys
from pathlib import Path

from ssllog.writer import LogWriter
from sslpb import ssl_gc_referee_message_pb2
from tests.ssllog.test_logfile import HEAD, T0, rec, referee, wrapper

S = 1_000_000_000
Referee = ssl_gc_referee_message_pb2.Referee
ROOT = Path(__file__).resolve().parents[2]


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "ssllog", *args], cwd=ROOT, capture_output=True, text=True,
        timeout=60, check=False,
    )


def small_log(p: Path) -> None:
    """10 s: cameras 0 and 1 at 10 Hz (each frame one ball + one blue robot), referee at
    1 Hz with STOP then FORCE_START, one type 1001 record, a 2 s silence of vision."""
    recs = []
    for i in range(100):
        t = T0 + i * S // 10
        if 40 <= i < 62:
            continue  # vision gap 3.9 s .. 6.2 s
        recs.append(rec(t, 4, wrapper(0, i)))
        recs.append(rec(t + 1000, 4, wrapper(1, i)))
    for s in range(10):
        cmd = Referee.STOP if s < 5 else Referee.FORCE_START
        recs.append(rec(T0 + s * S + 500, 3, referee(1 if s < 5 else 2, cmd)))
    recs.append(rec(T0 + 99 * S // 10 + 2000, 1001, b"ours"))
    recs.sort(key=lambda r: int.from_bytes(r[:8], "big"))
    p.write_bytes(HEAD + b"".join(recs))


def test_info(tmp_path: Path) -> None:
    p = tmp_path / "m.log"
    small_log(p)
    r = run("--cache-dir", str(tmp_path / "c"), "info", str(p))
    assert r.returncode == 0, r.stderr
    out = r.stdout
    assert "duration: 9.900 s" in out
    lines = [" ".join(line.split()) for line in out.splitlines()]
    assert "4 vision 2014 156" in lines
    assert "3 referee 2013 10" in lines
    assert "1001 touchline commands 1" in lines
    assert "camera 0: 78 frames, 7.9 Hz" in out and "camera 1: 78 frames" in out
    assert "teams: yellow Yel, blue Blu" in out
    assert "commands: FORCE_START x1, STOP x1" in out
    assert "stages: NORMAL_FIRST_HALF x1" in out
    assert "gaps (> 1 s without vision): 1" in out
    assert "3.900 s .. 6.200 s (2.300 s)" in out
    assert r.stderr == ""  # no progress without a tty


def test_export_csv_range(tmp_path: Path) -> None:
    p = tmp_path / "m.log"
    small_log(p)
    out = tmp_path / "o.csv"
    r = run("--cache-dir", str(tmp_path / "c"), "--progress", "export", str(p),
            "--from", "1", "--to", "2", "--csv", str(out))
    assert r.returncode == 0, r.stderr
    assert "100%" in r.stderr
    rows = list(csv.DictReader(out.open()))
    # frames 10..20 of camera 0 (t 1.0 .. 2.0) and 10..19 of camera 1 (+1 us): 21 frames x 2
    assert len(rows) == 42
    assert rows[0] == {
        "t_log_s": "1.000000", "t_capture": repr(10 / 60), "camera_id": "0",
        "frame_number": "10", "kind": "ball", "id": "", "x_mm": "100.0", "y_mm": "-50.0",
        "orientation_rad": "", "confidence": repr(float.fromhex("0x1.ccccccp-1")),
    }
    robot = rows[1]
    assert (robot["kind"], robot["id"], robot["x_mm"], robot["y_mm"]) == ("blue", "3", "1000.0",
                                                                          "500.0")
    assert robot["orientation_rad"] == "1.5"
    assert {r["camera_id"] for r in rows} == {"0", "1"}
    assert float(rows[-1]["t_log_s"]) <= 2.0


def test_errors_are_one_line(tmp_path: Path) -> None:
    p = tmp_path / "bad.log"
    p.write_bytes(b"garbage garbage garbage")
    r = run("--cache-dir", str(tmp_path / "c"), "info", str(p))
    assert r.returncode == 1 and r.stderr.startswith("ssllog: corrupt SSL log at byte 0")
    w = tmp_path / "w.log"
    lw = LogWriter(str(w))
    lw.write(T0, 4, wrapper(0, 0))
    lw.finish()
    r = run("--cache-dir", str(tmp_path / "c"), "export", str(w), "--csv", "-")
    assert r.returncode == 0 and r.stdout.count("\n") == 3  # header, ball, robot


def test_filtered_says_where_it_moved(tmp_path: Path) -> None:
    """The world model's re-run is the backend's command now (the log package does not import
    the backend): the old flag says so in one line instead of an argparse error."""
    p = tmp_path / "m.log"
    small_log(p)
    out = tmp_path / "f.csv"
    r = run("--cache-dir", str(tmp_path / "c"), "export", str(p), "--filtered", "paper",
            "--csv", str(out))
    assert r.returncode == 2 and not out.exists()
    assert r.stderr.count("\n") == 1 and "python -m backend.relog" in r.stderr


def test_index_builds_the_cache_with_progress_lines(tmp_path: Path) -> None:
    """``index`` (what the station runs as a child process): the cache afterwards opens
    without a scan; progress as 'progress F' lines on stdout, rising to 1; a bad file is one
    line on stderr and exit status 1."""
    import gzip

    from ssllog.logfile import LogFile

    p = tmp_path / "m.log.gz"
    plain = tmp_path / "plain.log"
    small_log(plain)
    p.write_bytes(gzip.compress(plain.read_bytes()))
    r = run("--cache-dir", str(tmp_path / "c"), "index", "--progress-lines", str(p))
    assert r.returncode == 0, r.stderr
    fractions = [float(line.split()[1]) for line in r.stdout.splitlines()]
    assert r.stdout.splitlines()[0].startswith("progress ")
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    with LogFile.open(str(p), tmp_path / "c", build=False) as lf:
        assert lf.counts[4] == 156
    bad = tmp_path / "bad.log"
    bad.write_bytes(b"garbage garbage garbage")
    r = run("--cache-dir", str(tmp_path / "c"), "index", "--progress-lines", str(bad))
    assert r.returncode == 1
    assert r.stderr.startswith("ssllog: corrupt SSL log at byte 0") and r.stderr.count("\n") == 1
