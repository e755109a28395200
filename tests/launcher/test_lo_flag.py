"""The launcher's warning about a lo without the MULTICAST flag (the league's Go tools skip
such an interface; our own sockets do not need the flag)."""

from __future__ import annotations

from launcher.__main__ import LO_FLAG_WARNING, lo_flag_warning


def test_a_loopback_station_on_a_lo_without_the_flag_is_warned() -> None:
    assert lo_flag_warning("127.0.0.1", lambda name: False) == LO_FLAG_WARNING
    assert "ip link set lo multicast on" in LO_FLAG_WARNING


def test_no_warning_with_the_flag_or_when_unknown() -> None:
    assert lo_flag_warning("127.0.0.1", lambda name: True) is None
    assert lo_flag_warning("127.0.0.1", lambda name: None) is None  # not Linux: cannot tell


def test_no_warning_for_a_station_on_a_field_network() -> None:
    asked: list[str] = []

    def flag(name: str) -> bool:
        asked.append(name)
        return False

    assert lo_flag_warning("192.0.2.2", flag) is None
    assert asked == []
