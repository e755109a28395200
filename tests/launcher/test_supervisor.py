"""The one supervisor (launcher.supervisor) with real child processes: mirror-order stop,
restart of a crashed child and giving up on one that keeps crashing, logs per child."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from launcher.supervisor import (
    BACKOFF_MAX_S,
    BACKOFF_STEP_S,
    RESTARTED_FLAG,
    STEADY_S,
    Child,
    Ports,
    StationConfig,
    Supervisor,
    command_lines,
)
from tests.waiting import wait_until

# a child that notes when it is asked to stop, then exits
_POLITE = """
import signal, sys, time
def bye(*_):
    with open(sys.argv[1], "a") as f:
        f.write(sys.argv[2] + "\\n")
    sys.exit(0)
signal.signal(signal.SIGTERM, bye)
print("hello from", sys.argv[2], flush=True)
for _ in range(600):
    time.sleep(0.1)
"""


def _polite(name: str, note: Path) -> Child:
    return Child(name, [sys.executable, "-c", _POLITE, str(note), name])


def test_children_stop_in_mirror_order_and_log_to_their_files(tmp_path: Path) -> None:
    note = tmp_path / "stopped.txt"
    sup = Supervisor([_polite(n, note) for n in ("fieldsim", "relay", "backend")],
                     log_dir=tmp_path / "logs", detach=True)
    sup.start()
    try:
        wait_until(lambda: all("hello" in sup.log_tail(n)
                               for n in ("fieldsim", "relay", "backend")), 10.0, 0.05)
    finally:
        sup.stop(timeout_s=5.0)
    assert note.read_text().split() == ["backend", "relay", "fieldsim"]
    assert sup.exit_codes == {"backend": 0, "relay": 0, "fieldsim": 0}
    assert sup.watch() == "fieldsim exited with 0"  # without restart: a dead child is reported


def test_a_crashed_child_is_restarted_and_one_that_keeps_crashing_is_given_up(
        tmp_path: Path) -> None:
    crash = Child("relay", [sys.executable, "-c", "import sys; sys.exit(3)"])
    sup = Supervisor([crash], log_dir=tmp_path, restart=True, max_restarts=2)
    sup.start()
    verdicts = []
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        v = sup.watch()
        verdicts.append(v)
        if v is not None:
            break
        time.sleep(0.05)
    sup.stop(timeout_s=5.0)
    assert crash.restarts == 2
    assert verdicts[-1] == "relay exited 3 and keeps crashing; giving up"


def test_a_restart_tells_the_child_and_a_start_does_not(tmp_path: Path) -> None:
    """The backend learns it was restarted after a crash (it takes the operator's arming back
    then, docs/security.md) from a flag only the supervisor's restart adds."""
    argv_note = tmp_path / "argv.txt"
    child = Child("backend", [sys.executable, "-c",
                              "import sys; open(sys.argv[1], 'a').write(' '.join(sys.argv[2:])"
                              " + '\\n'); sys.exit(1 if len(sys.argv) == 3 else 0)",
                              str(argv_note), "--port=1"], restart_args=["--restarted"])
    sup = Supervisor([child], restart=True, max_restarts=5)
    sup.start()
    try:
        # the first run exits 1; the watch that restarts it passes the flag
        deadline = time.monotonic() + 20
        while child.restarts == 0 and time.monotonic() < deadline:
            sup.wait_exit(1.0)
            assert sup.watch() is None
        wait_until(lambda: argv_note.exists() and len(argv_note.read_text().splitlines()) >= 2,
                   10.0, 0.05)
    finally:
        sup.stop(timeout_s=5.0)
    assert argv_note.read_text().splitlines()[:2] == ["--port=1", "--port=1 --restarted"]
    backend = command_lines(StationConfig(), Ports.isolated(None))[-1]
    assert backend.restart_args == [RESTARTED_FLAG] and backend.standby_args == ["--standby"]


def test_a_child_that_crashed_in_use_is_restarted_at_once_and_a_crash_loop_backs_off() -> None:
    now = 1000.0
    steady = Child("backend", [], started=now - STEADY_S, history=[now])
    assert steady.restart_delay_s(now) == 0.0  # it ran: the robots wait for it
    young = Child("backend", [], started=now - 1.0, history=[now])
    assert young.restart_delay_s(now) == BACKOFF_STEP_S  # it died at its start: a pause
    looping = Child("backend", [], started=now - 1.0,
                    history=[now - 50.0 + k for k in range(20)] + [now])
    assert looping.restart_delay_s(now) == BACKOFF_MAX_S
    # restarts more than a minute ago do not count
    old = Child("backend", [], started=now - 1.0, history=[now - 300.0, now - 200.0, now])
    assert old.restart_delay_s(now) == BACKOFF_STEP_S


def test_the_exit_of_a_child_wakes_the_watch(tmp_path: Path) -> None:
    """``wait_exit`` returns when a child exits, not at its timeout (the launcher's loop
    polled every 0.2 s): with an hour's timeout, this test would hang (and time out) if the
    exit did not wake it."""
    gate = tmp_path / "go"
    child = Child("relay", [sys.executable, "-c",
                            "import os, sys, time\n"
                            "while not os.path.exists(sys.argv[1]): time.sleep(0.01)",
                            str(gate)])
    sup = Supervisor([_polite("backend", tmp_path / "note"), child])
    sup.start()
    try:
        assert child.pidfd is not None  # Linux >= 5.3
        assert not sup.dead()
        gate.write_text("")
        sup.wait_exit(3600.0)
        assert sup.dead() == [child]
    finally:
        sup.stop(timeout_s=5.0)


# a child that notes how it runs; with --standby it waits for its line first, as the backend
_SPARE = """
import sys, time
note, args = sys.argv[1], sys.argv[2:]
if "--standby" in args:
    line = sys.stdin.readline()
    with open(note, "a") as f:
        f.write("spare told " + (line.strip() or "nothing") + "\\n")
    if not line.startswith("start"):
        sys.exit(0)
    args += line.split()[1:]
with open(note, "a") as f:
    f.write("running " + " ".join(args) + "\\n")
time.sleep(600)
"""


def test_a_warm_spare_takes_over_with_the_restart_flags(tmp_path: Path) -> None:
    import os
    import signal

    note = tmp_path / "note.txt"
    child = Child("backend", [sys.executable, "-c", _SPARE, str(note), "--port=1"],
                  restart_args=["--restarted"], standby_args=["--standby"])
    sup = Supervisor([child], restart=True, standby=True, spare_after_s=0.0)
    sup.start()
    try:
        wait_until(lambda: note.exists() and "running" in note.read_text(), 10.0, 0.05)
        wait_until(lambda: sup.watch() is None and child.spare is not None, 10.0, 0.05)
        assert child.spare is not None and child.proc is not None
        spare, first = child.spare.pid, child.proc.pid
        os.kill(first, signal.SIGKILL)
        sup.wait_exit(3600.0)
        assert sup.watch() is None
        assert child.proc.pid == spare and child.restarts == 1  # no new process: the spare
        wait_until(lambda: "running --port=1 --standby --restarted" in note.read_text(), 10.0, 0.05)
        # and the next spare
        wait_until(lambda: sup.watch() is None and child.spare is not None, 10.0, 0.05)
    finally:
        sup.stop(timeout_s=5.0)
    lines = note.read_text().splitlines()
    assert lines == ["running --port=1", "spare told start --restarted",
                     "running --port=1 --standby --restarted", "spare told nothing"], lines
    assert child.spare is None


def test_command_lines_of_the_station() -> None:
    ports = Ports.isolated(None)
    kids = command_lines(StationConfig(sim="none", output="robot-box", our_team="yellow",
                                       backend_args=["--play", "idle"]), ports)
    assert [c.name for c in kids] == ["relay", "backend"]
    relay, backend = (c.argv for c in kids)
    assert relay[relay.index("--output") + 1] == "robot-box"
    assert relay[relay.index("--sub") + 1] == ports.relay_sub
    assert backend[backend.index("--relay-sub") + 1] == ports.relay_sub
    assert backend[backend.index("--our-team") + 1] == "yellow"
    assert backend[-2:] == ["--play", "idle"]
    # tracked vision: loopback only (no --tracker-out), to the isolated port
    assert "--tracker-out" not in relay
    assert relay[relay.index("--tracker-out-local") + 1] == f"224.5.23.2:{ports.tracker}"
    assert ports.tracker != 10010
    # real robots: both the relay and the backend require arming
    assert "--require-arming" in relay and "--require-arming" in backend


def test_arming_is_required_for_anything_but_the_builtin_simulator() -> None:
    ports = Ports.isolated(None)
    for sim, output, required in (("builtin", "sim", False), ("builtin", "grsim", True),
                                  ("none", "sim", True), ("none", "robot-box", True)):
        kids = command_lines(StationConfig(sim=sim, output=output), ports)
        relay, backend = (c.argv for c in kids[-2:])
        assert ("--require-arming" in relay) is required, (sim, output)
        assert ("--require-arming" in backend) is required, (sim, output)


def test_free_ports_are_never_handed_out_twice_in_one_process() -> None:
    """Binding port 0 and closing lets the kernel hand the same number out again (10 repeats in
    500 calls measured here); a station's HTTP port and a relay's ZeroMQ port once collided so."""
    from launcher.supervisor import free_tcp_port, free_udp_port

    tcp = [free_tcp_port() for _ in range(500)]
    udp = [free_udp_port() for _ in range(500)]
    assert len(set(tcp)) == len(tcp)
    assert len(set(udp)) == len(udp)
    ports = Ports.isolated(None)
    zmq_ports = [int(e.rsplit(":", 1)[1]) for e in (ports.relay_pub, ports.relay_sub)]
    assert ports.http not in zmq_ports and zmq_ports[0] != zmq_ports[1]


def _gone(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return True
    return state in ("Z", "X")  # ended, not yet reaped by whoever adopted it


def test_a_killed_launcher_leaves_no_process_behind() -> None:
    """SIGKILL of ``python -m launcher`` (a test fixture's last resort when the station does not
    come up): the kernel stops fieldsim, the relay and the backend too (they were left running)."""
    import json
    import os
    import signal
    import subprocess

    root = Path(__file__).resolve().parents[2]
    proc = subprocess.Popen([sys.executable, "-m", "launcher", "--isolated"], cwd=root,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    pids: dict[str, int] = {}
    try:
        assert proc.stdout is not None
        for line in proc.stdout:  # bounded by the launcher's own start-up (it exits on failure)
            if line.startswith("TOUCHLINE_PIDS "):
                pids = json.loads(line.split(" ", 1)[1])
                break
        assert set(pids) >= {"fieldsim", "relay", "backend"}, pids
        assert not any(_gone(p) for p in pids.values())
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    try:
        wait_until(lambda: all(_gone(p) for p in pids.values()), 20.0, 0.05)
    finally:  # a failure must not leave them running either
        for p in pids.values():
            if not _gone(p):
                os.kill(p, signal.SIGKILL)
