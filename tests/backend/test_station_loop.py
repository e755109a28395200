"""The station thread's GIL switch interval and its bench override."""

from __future__ import annotations

import logging

import pytest

from backend.station_loop import (
    DEFAULT_SWITCH_INTERVAL_S,
    SWITCH_INTERVAL_ENV,
    switch_interval_s,
)


def test_switch_interval_defaults_and_takes_a_number_of_seconds(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(SWITCH_INTERVAL_ENV, raising=False)
    assert switch_interval_s() == DEFAULT_SWITCH_INTERVAL_S
    monkeypatch.setenv(SWITCH_INTERVAL_ENV, "0.0001")
    assert switch_interval_s() == 0.0001


@pytest.mark.parametrize("raw", ["fast", "0", "-0.001", "nan", "inf", "2"])
def test_a_bad_switch_interval_is_refused_with_a_warning(
        raw: str, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    monkeypatch.setenv(SWITCH_INTERVAL_ENV, raw)
    with caplog.at_level(logging.WARNING, logger="touchline.station"):
        assert switch_interval_s() == DEFAULT_SWITCH_INTERVAL_S
    assert SWITCH_INTERVAL_ENV in caplog.text
