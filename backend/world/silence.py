"""All vision lost, told apart from one robot unseen.

One robot unseen for a while is normal (occlusion) and is the filter's business. Every camera
falling silent at once (the vision PC or its switch died) is not: the robots would drive on
their last commands until ``safety.vision_stale_s`` (0.3 s). ``CameraSilence`` keeps each
camera's last frames by the receive clock (the relay's arrival stamps, never the capture
times, which a camera's own clock may skew) and says from when the whole vision counts as
lost: ``PERIODS`` frame periods of the camera's measured rate after its last frame, at most
``MAX_S``, less ``SEND_MARGIN_S`` for the stop to reach the robots; for several cameras,
when the last of them is past its time. This holds only while every camera heard lately
delivers at ``MIN_RATE_HZ`` or more: with a slower camera, or one not measured yet, the
stop stays ``vision_stale_s``'s.

Pure: frames in, times out, no clock of its own (the caller says what time it is: the wall
clock live, the log's time at the playhead in replay). Rates are computed when asked (the
control asks only once the world is ``MIN_S`` old), a frame costs an append.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

#: the whole vision is lost after this many frame periods without any frame ...
PERIODS = 6
#: ... at most this long after the last frame (the stop leaves the relay by then) ...
MAX_S = 0.1
#: ... decided this much sooner: the timer's lateness, the pass, ZeroMQ and the relay's
#: output (bench/vision_loss_bench.py on 2 cores at load 10: decided 0.5-1 ms late, up to
#: 5-10 ms when the machine is short of CPU; then 1-2 ms to the relay's datagram)
SEND_MARGIN_S = 0.02
#: ... and never sooner than this (a camera faster than the league's 75 Hz, or a burst,
#: must not stop the robots for a 2-frame gap; the control's wake-up checks rely on it)
MIN_S = 0.05
#: the rule holds only while every camera heard lately was at least this fast
MIN_RATE_HZ = 30.0
#: a camera's rate is measured over its last frames (0.25 s at 60 Hz); with fewer than
#: ``MIN_FRAMES`` it is not known yet
RATE_FRAMES = 16
MIN_FRAMES = 8
#: a camera silent this long before the newest frame of another one no longer counts (one
#: camera of four died: the others go on, and its rate no longer matters)
RETIRE_S = 1.0


def lost_after_s(rate_hz: float) -> float | None:
    """The silence after which the vision of a camera at ``rate_hz`` counts as lost; None
    below ``MIN_RATE_HZ`` (the ``vision_stale_s`` rule)."""
    if not rate_hz >= MIN_RATE_HZ:  # (NaN too)
        return None
    return max(MIN_S, min(PERIODS / rate_hz, MAX_S) - SEND_MARGIN_S)


@dataclass(frozen=True, slots=True)
class Lost:
    """Every camera silent: for how long, how fast the cameras were, and the rule's time."""

    silent_s: float  # since the last frame of any camera
    rate_hz: float  # the fastest camera before
    after_s: float  # the silence that counts as lost

    def reason(self) -> str:
        """What ``halt_reason`` and the health say."""
        silent = (f"{self.silent_s * 1000:.0f} ms" if self.silent_s < 1.0
                  else f"{self.silent_s:.1f} s")
        return f"no vision: every camera silent for {silent} (was {self.rate_hz:.0f} Hz)"


class _Camera:
    __slots__ = ("times",)

    def __init__(self) -> None:
        self.times: deque[int] = deque(maxlen=RATE_FRAMES)  # receive times, ns


class CameraSilence:
    """Each camera's last frames by the receive clock, and from when the whole vision counts
    as lost (module docstring)."""

    def __init__(self, max_camera_id: int = 63) -> None:
        self.max_camera_id = max_camera_id  # the world model's bound: others are not cameras
        self._cams: dict[int, _Camera] = {}
        self.newest_ns = 0  # the last frame of any camera
        self._cache: tuple[int | None, float] | None = (None, 0.0)  # deadline, fastest rate

    def reset(self) -> None:
        """Time jumped (a replay opened or seeked, back to live): measured anew."""
        self._cams.clear()
        self.newest_ns = 0
        self._cache = (None, 0.0)

    def frame(self, camera_id: int, receive_time_ns: int) -> None:
        """A detection frame of ``camera_id`` arrived at ``receive_time_ns``."""
        if not 0 <= camera_id <= self.max_camera_id or receive_time_ns <= 0:
            return
        cam = self._cams.get(camera_id)
        if cam is None:
            cam = self._cams[camera_id] = _Camera()
        times = cam.times
        if times and receive_time_ns < times[-1]:
            times.clear()  # the clock went back (stepped): its rate is measured anew
        times.append(receive_time_ns)
        if receive_time_ns > self.newest_ns:
            self.newest_ns = receive_time_ns
        self._cache = None

    def _current(self) -> list[tuple[int, _Camera]]:
        """The cameras heard within ``RETIRE_S`` of the newest frame."""
        oldest = self.newest_ns - int(RETIRE_S * 1e9)
        return [(i, c) for i, c in self._cams.items() if c.times and c.times[-1] >= oldest]

    @staticmethod
    def _rate_hz(cam: _Camera) -> float:
        """Frames a second over the camera's last frames; 0.0 while not known."""
        times = cam.times
        n = len(times)
        span = times[-1] - times[0] if n else 0
        return (n - 1) * 1e9 / span if n >= MIN_FRAMES and span > 0 else 0.0

    def _compute(self) -> tuple[int | None, float]:
        deadline: int | None = None
        fastest = 0.0
        for _, cam in self._current():
            rate = self._rate_hz(cam)
            after = lost_after_s(rate)
            if after is None:  # a slow camera, or one not measured yet: vision_stale_s's
                return None, 0.0
            until = cam.times[-1] + round(after * 1e9)
            deadline = until if deadline is None else max(deadline, until)
            fastest = max(fastest, rate)
        return deadline, fastest

    def deadline_ns(self) -> int | None:
        """The receive-clock time from which the whole vision counts as lost; None when the
        rule does not hold (no camera yet, or a camera heard lately is slower than
        ``MIN_RATE_HZ`` or not measured yet)."""
        if self._cache is None:
            self._cache = self._compute()
        return self._cache[0]

    def lost_after_s(self) -> float | None:
        """How long after the last frame the vision counts as lost now (None: the rule does
        not hold)."""
        d = self.deadline_ns()
        return None if d is None else (d - self.newest_ns) / 1e9

    def lost(self, now_ns: int) -> Lost | None:
        """Every camera silent past its time at ``now_ns`` (the receive clock), else None."""
        d = self.deadline_ns()
        if d is None or now_ns < d:
            return None
        assert self._cache is not None
        return Lost((now_ns - self.newest_ns) / 1e9, self._cache[1],
                    (d - self.newest_ns) / 1e9)

    def rates_hz(self) -> dict[int, float]:
        """Each camera heard lately: its measured rate (0.0: not known yet)."""
        return {i: self._rate_hz(c) for i, c in sorted(self._current())}
