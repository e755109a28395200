import os
import select
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from sslnet.multicast import (
    IFF_MULTICAST,
    interface_multicast_flag,
    loopback_multicast_ok,
    open_multicast_receiver,
    open_multicast_sender,
    open_udp_server,
)


def test_two_receivers_on_one_group_port_both_get_each_datagram() -> None:
    import random

    port = random.randrange(20000, 30000)
    a = open_multicast_receiver("224.5.23.2", port)
    b = open_multicast_receiver("224.5.23.2", port)
    tx = open_multicast_sender()
    try:
        tx.sendto(b"hello", ("224.5.23.2", port))
        for s in (a, b):
            ready, _, _ = select.select([s], [], [], 2.0)
            assert ready and s.recv(64) == b"hello"
    finally:
        for s in (a, b, tx):
            s.close()


def test_a_second_command_server_on_the_same_port_fails_loudly() -> None:
    s = open_udp_server("127.0.0.1", 0)
    try:
        with pytest.raises(OSError):
            open_udp_server("127.0.0.1", s.getsockname()[1])
    finally:
        s.close()


def test_loopback_multicast_check() -> None:
    assert loopback_multicast_ok()


def _sysfs_with_lo_flags(tmp_path: Path, flags: str) -> str:
    (tmp_path / "lo").mkdir()
    (tmp_path / "lo" / "flags").write_text(flags + "\n")
    return str(tmp_path)


@pytest.mark.parametrize(("flags", "expected"), [
    ("0x1009", True),   # LOOPBACK, UP, MULTICAST: what the league's tools need
    ("0x9", False),     # a fresh namespace's lo: no MULTICAST
    ("0x11043", True),  # an ethernet interface
    ("garbage", None),
])
def test_interface_multicast_flag_reads_the_flags(
    tmp_path: Path, flags: str, expected: bool | None
) -> None:
    assert interface_multicast_flag("lo", sysfs=_sysfs_with_lo_flags(tmp_path, flags)) is expected


def test_interface_multicast_flag_of_an_unknown_interface_is_none(tmp_path: Path) -> None:
    assert interface_multicast_flag("nosuch0", sysfs=str(tmp_path)) is None


@pytest.mark.skipif(not os.path.exists("/sys/class/net/lo/flags"), reason="no Linux sysfs")
def test_interface_multicast_flag_of_this_machines_lo_is_known() -> None:
    assert interface_multicast_flag("lo") in (True, False)


_ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.skipif(
    os.geteuid() != 0 or not shutil.which("unshare") or not shutil.which("ip"),
    reason="needs root, unshare and ip (a network namespace of its own)")
def test_setup_multicast_sets_the_lo_flag_that_the_league_tools_need() -> None:
    # A fresh network namespace's lo has no MULTICAST flag; our own check passes without it
    # (IP_MULTICAST_IF, a join by address), so the script once stopped there and left
    # ssl-vision-client and the game controller deaf. Its own sysfs shows that lo's flags.
    script = (
        "mount -t sysfs sysfs /sys && ip link set lo up && cat /sys/class/net/lo/flags && "
        f"{_ROOT / 'scripts' / 'setup-multicast.sh'} {sys.executable} && "
        "cat /sys/class/net/lo/flags")
    done = subprocess.run(["unshare", "--net", "--mount", "sh", "-c", script],
                          capture_output=True, text=True, timeout=60, cwd=_ROOT, check=False)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.split()
    before, after = int(lines[0], 16), int(lines[-1], 16)
    assert not before & IFF_MULTICAST
    assert after & IFF_MULTICAST
