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

Pure code: no I/O, no wall clock (the receive time comes with the frame)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass
class ClockConfig:
    max_ahead_s: float = 0.1  # a capture this much after its expected time is out of range
    max_late_s: float = 0.5  # a capture this much before it (latency, a stuck frame): out
    resync_frames: int = 8  # consecutive out-of-range frames agreeing: the camera's new clock


@dataclass
class ClockVerdict:
    """What :meth:`CameraClocks.check` made of one frame."""

    t_local: float | None  # the capture time on the receive clock; None: dropped
    resynced: bool = False  # this frame re-synchronised its camera's clock
    skew_s: float = 0.0  # how far the frame was from its camera's clock (when dropped)


@dataclass
class _Camera:
    offset: float | None = None  # receive - capture (s); None until learnt
    pending: list[float] = field(default_factory=list)  # out-of-range offsets in a row


class CameraClocks:
    """One clock offset per camera; see the module text."""

    def __init__(self, config: ClockConfig | None = None) -> None:
        self.config = config or ClockConfig()
        self._cams: dict[int, _Camera] = {}
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
        d = receive_time_ns / 1e9 - t_capture
        cam = self._cams.get(camera_id)
        if cam is None:
            cam = self._cams[camera_id] = _Camera()
        off = cam.offset
        if off is None:
            for off in [0.0, *(o.offset for o in self._cams.values() if o.offset is not None)]:
                if self._fits(d, off):
                    cam.offset = off
                    cam.pending.clear()
                    return ClockVerdict(t_capture + off)
        else:
            c = self.config
            if -c.max_ahead_s <= d - off <= c.max_late_s:  # _fits, inline: every frame
                if cam.pending:
                    cam.pending.clear()
                return ClockVerdict(t_capture + off)
        # out of range: dropped, unless the camera keeps saying the same (a new clock)
        c = self.config
        if cam.pending and not (max(cam.pending[0], d) - min(cam.pending[0], d)
                                <= c.max_late_s + c.max_ahead_s):
            cam.pending.clear()  # not the same new clock: start again from this frame
        cam.pending.append(d)
        if len(cam.pending) >= c.resync_frames:
            # the smallest offset seen is the least delayed frame: mapped times stay <= receive
            cam.offset = min(cam.pending)
            cam.pending.clear()
            self.resyncs += 1
            return ClockVerdict(t_capture + cam.offset, resynced=True)
        self.dropped += 1
        skew = d - (cam.offset if cam.offset is not None else 0.0)
        return ClockVerdict(None, skew_s=skew)
