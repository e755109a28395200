"""The health's lines when the vision is lost: every camera silent says so once, with the
reason control gives in halt_reason; a world not updated although frames arrive (dropped by
the world model) keeps its own line."""

from __future__ import annotations

from typing import Any

from backend import contract
from backend.views import _warnings

SILENT = "no vision: every camera silent for 120 ms (was 60 Hz)"
RELAY = {"alive": True, "age_s": 0.1}


def _world(**over: Any) -> contract.WorldHealth:
    w: contract.WorldHealth = {
        "age_s": 0.12, "stale": True, "rejected": {}, "recent_rejections": {},
        "last_rejection": "", "clock_resyncs": 0, "camera_clock_offsets_s": {},
        "camera_pairs": [], "camera_rates_hz": {"0": 60.0}, "lost_after_s": 0.08,
        "vision_lost": SILENT}
    w.update(over)  # type: ignore[typeddict-item]
    return w


def test_every_camera_silent_is_one_line_with_the_reason() -> None:
    # (the vision stream's last datagram is 0.12 s old: under the 1 s of "no vision for")
    lines = _warnings({"last_age_s": 0.12}, RELAY, None, _world())
    assert lines == [f"{SILENT}: robots stopped"]


def test_frames_that_arrive_but_never_merge_keep_their_own_line() -> None:
    lines = _warnings({"last_age_s": 0.01}, RELAY, None,
                      _world(age_s=0.4, vision_lost=None, last_rejection="time out of range"))
    assert lines == ["world not updated for 0.4 s although vision arrives: robots stopped "
                     "(time out of range)"]


def test_in_replay_the_logs_silence_is_no_warning() -> None:
    assert _warnings({"last_age_s": 0.12}, RELAY, None, _world(), replaying=True) == []
