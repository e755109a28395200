"""Camera clocks checked against the receive clock: a capture time from the wire is never
trusted alone.

Every detection frame carries the camera's capture time (``t_capture``, Unix s, the vision
PC's clock) and the relay's receive time (``receive_time_ns``, this machine's clock). Per
camera, ``receive - capture`` is the camera's *offset*: the latency (ms) plus any difference
between the two clocks. A frame is accepted when its offset is within
``[offset - max_ahead_s, offset + max_late_s]`` of the camera's offset; its capture time is
then mapped onto the receive clock (``t_capture + offset``), so every time inside the world
model is close to the receive clock and a far-off value cannot become "the latest time".

* A camera whose clock agrees with ours (offset within the window around 0: the vision PC is
  synchronised, or it is the built-in simulator on this machine) keeps offset 0: its times are
  used unchanged, and the cameras of one source stay exactly comparable.
* A camera whose clock differs from ours is learnt once ``resync_frames`` consecutive frames
  agree on a new offset; the same happens when a camera's clock jumps (the vision PC's clock
  was set, a log is replayed, a camera restarts): it is *re-synchronised*, like TIGERs' camera
  filter resets on frame jumps. A new camera first tries the offsets of the cameras known
  already (one vision PC, one clock).
* A single frame far from its camera's clock (a byte flip in ``t_capture``, a frame from the
  future) is dropped and counted; it changes nothing.
* A clock that drifts slowly against ours is followed, as real SSL trackers follow each
  camera's offset: grSim stamps its simulated time, which runs at least 2 % slower than the
  wall clock (1/60 s per 17 ms timer tick; 3-6 % on a busy machine, unevenly), so its offset
  grew by 20-60 ms a second and its frames left the window every 10-25 s (dropped until a
  re-synchronisation, each camera onto an offset of its own). Per clock (the
  cameras sharing an offset move together: their times stay exactly comparable) the least
  delay of its frames is taken per block of ``follow_block_s``; while the greater of the last
  two blocks' least delays (one odd frame does not count) is outside ``[-follow_ahead_s,
  follow_late_s]``, the offset's rate of change is corrected by what is outside, up to
  ``follow_max_rate`` (the offset a linear function of the capture time: no jump). A clock
  whose frames stay inside (one that agrees with ours, or was learnt and does not drift)
  never moves: its times are as before.

Pure code: no I/O, no wall clock (the receive time comes with the frame)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass
class ClockConfig:
    max_ahead_s: float = 0.1  # a capture this much after its expected time is out of range
    max_late_s: float = 0.5  # a capture this much before it (latency, a stuck frame): out
    resync_frames: int = 8  # consecutive out-of-range frames agreeing: the camera's new clock
    follow_block_s: float = 0.25  # a clock's least delay is taken per block this long
    follow_late_s: float = 0.05  # a least delay above this: the clock runs slow, followed
    follow_ahead_s: float = 0.01  # one below minus this: the clock runs fast, followed
    follow_max_rate: float = 0.2  # the fastest drift followed (s/s); faster: re-synchronised


@dataclass
class ClockVerdict:
    """What :meth:`CameraClocks.check` made of one frame."""

    t_local: float | None  # the capture time on the receive clock; None: dropped
    resynced: bool = False  # this frame re-synchronised its camera's clock
    skew_s: float = 0.0  # how far the frame was from its camera's clock (when dropped)


@dataclass
class _Clock:
    """One capture clock (a vision PC, a simulator), shared by the cameras on it: the offset
    (receive - capture, s) at capture time ``anchor`` is ``base``, changing by ``rate`` s/s."""

    base: float
    rate: float = 0.0
    anchor: float = 0.0
    block_end: float = -math.inf  # receive time (s) the current block ends
    block_min: float = math.inf  # least delay (d - offset) of the block so far
    last_min: float = math.inf  # least delay of the block before

    def offset(self, t_capture: float) -> float:
        return self.base + self.rate * (t_capture - self.anchor) if self.rate else self.base


@dataclass
class _Camera:
    clock: _Clock | None = None  # None until learnt
    pending: list[float] = field(default_factory=list)  # out-of-range offsets in a row

    @property
    def offset(self) -> float | None:
        return None if self.clock is None else self.clock.base


class CameraClocks:
    """One clock offset per camera; see the module text."""

    def __init__(self, config: ClockConfig | None = None) -> None:
        self.config = config or ClockConfig()
        self._cams: dict[int, _Camera] = {}
        #: the clock that agrees with ours (offset 0), for every camera that fits it
        self._zero = _Clock(0.0)
        self.dropped = 0  # frames dropped: capture time out of range
        self.resyncs = 0  # camera clocks learnt or re-synchronised after a jump

    def offsets(self) -> dict[int, float | None]:
        return {c: cam.offset for c, cam in sorted(self._cams.items())}

    def forget(self, camera_id: int) -> None:
        self._cams.pop(camera_id, None)

    def _fits(self, d: float, offset: float) -> bool:
        c = self.config
        return -c.max_ahead_s <= d - offset <= c.max_late_s

    def check(self, camera_id: int, t_capture: float, receive_time_ns: int) -> ClockVerdict:
        if not math.isfinite(t_capture):
            self.dropped += 1
            return ClockVerdict(None, skew_s=math.inf)
        if receive_time_ns <= 0:
            # no receive clock (frames fed by a program, not the relay): nothing to check
            return ClockVerdict(t_capture)
        recv = receive_time_ns / 1e9
        d = recv - t_capture
        cam = self._cams.get(camera_id)
        if cam is None:
            cam = self._cams[camera_id] = _Camera()
        clk = cam.clock
        if clk is None:
            for known in [self._zero, *self._clocks()]:
                off = known.offset(t_capture)
                if self._fits(d, off):
                    cam.clock = known
                    cam.pending.clear()
                    return ClockVerdict(t_capture + off)
        else:
            c = self.config
            off = clk.base + clk.rate * (t_capture - clk.anchor) if clk.rate else clk.base
            x = d - off
            if -c.max_ahead_s <= x <= c.max_late_s:  # _fits, inline: every frame
                if cam.pending:
                    cam.pending.clear()
                if x < clk.block_min:
                    clk.block_min = x
                if recv >= clk.block_end:
                    self._follow(clk, recv, t_capture)
                return ClockVerdict(t_capture + off)
        # out of range: dropped, unless the camera keeps saying the same (a new clock)
        c = self.config
        if cam.pending and not (max(cam.pending[0], d) - min(cam.pending[0], d)
                                <= c.max_late_s + c.max_ahead_s):
            cam.pending.clear()  # not the same new clock: start again from this frame
        cam.pending.append(d)
        if len(cam.pending) >= c.resync_frames:
            # the smallest offset seen is the least delayed frame: mapped times stay <= receive
            cam.clock = _Clock(min(cam.pending))
            cam.pending.clear()
            self.resyncs += 1
            return ClockVerdict(t_capture + cam.clock.base, resynced=True)
        self.dropped += 1
        skew = d - (cam.clock.offset(t_capture) if cam.clock is not None else 0.0)
        return ClockVerdict(None, skew_s=skew)

    def _clocks(self) -> list[_Clock]:
        """The clocks of the cameras known, each once."""
        out: list[_Clock] = []
        for cam in self._cams.values():
            if cam.clock is not None and all(cam.clock is not k for k in out):
                out.append(cam.clock)
        return out

    def _follow(self, clk: _Clock, recv: float, t_capture: float) -> None:
        """A block of ``clk``'s frames is over: while the least delay of the last two blocks
        is outside the band, the offset's rate is corrected, from this capture on."""
        c = self.config
        low, before = clk.block_min, clk.last_min
        clk.last_min, clk.block_min = low, math.inf
        first = clk.block_end == -math.inf
        clk.block_end = recv + c.follow_block_s
        floor = max(low, before)
        if first or not math.isfinite(floor):
            return
        if floor > c.follow_late_s:
            excess = floor - c.follow_late_s
        elif floor < -c.follow_ahead_s:
            excess = floor + c.follow_ahead_s
        else:
            return
        # the drift left over (the least delay's change from the block before) cancelled,
        # and a quarter of what is outside the band taken back per block
        rate = clk.rate + (low - before + 0.25 * excess) / c.follow_block_s
        rate = max(-c.follow_max_rate, min(c.follow_max_rate, rate))
        clk.base, clk.anchor, clk.rate = clk.offset(t_capture), t_capture, rate
