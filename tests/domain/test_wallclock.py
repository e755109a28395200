"""One way to write wall-clock times: an operator's message in the station's local time, data
in UTC (domain/wallclock.py)."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator

import pytest

from backend.operators import DrivingRefused, Who
from domain import wallclock

T = 1795960987.25  # 2026-11-29 14:03:07.250 UTC


@pytest.fixture
def tokyo() -> Iterator[None]:
    """A local time zone 9 h from UTC, so a local time and a UTC one cannot be mistaken."""
    old = os.environ.get("TZ")
    os.environ["TZ"] = "Asia/Tokyo"
    time.tzset()
    try:
        yield
    finally:
        if old is None:
            del os.environ["TZ"]
        else:
            os.environ["TZ"] = old
        time.tzset()


def test_operators_read_local_time_data_is_utc(tokyo: None) -> None:
    assert wallclock.clock(T) == "23:03:07"
    assert wallclock.date_clock(T) == "2026-11-29 23:03:07"
    assert wallclock.file_stamp(T) == "20261129-230307"
    assert wallclock.iso_utc(T) == "2026-11-29T14:03:07.250+00:00"


def test_a_driving_refusal_names_the_local_time(tokyo: None) -> None:
    # it said the UTC time (gmtime) while the e-stop and arming messages said the local one
    ana = Who(key="k", name="Ana", role="operator", address="10.0.0.7")
    refused = DrivingRefused("blue", ana, T)
    assert "since 23:03:07" in str(refused)
