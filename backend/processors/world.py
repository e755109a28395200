"""The world processor: camera frames merged into the world model."""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable

from sslnet import streams

from .. import topics
from ..bus import DataBus, Reader
from ..params.model import StationParams
from ..processor import OnTopic, Processor
from ..world.model import WorldModel
from ..world.silence import CameraSilence
from ..world.state import Team, WorldState
from .common import LatencyStage, badlog


class WorldProcessor(Processor):
    """Merges camera frames into the world, on every new frame. The world is written only when
    a frame was merged: frames that are all dropped (capture time far from the receive clock,
    a camera id that cannot be) leave the world to age, so the lost-vision stop fires."""

    name = "world-model"

    def __init__(self, bus: DataBus, model: WorldModel | None = None) -> None:
        detections = bus.of(topics.VISION_DETECTIONS)
        super().__init__(OnTopic(detections))
        self.reader = Reader(detections)
        self.world = bus.of(topics.WORLD)
        self.geometry = bus.of(topics.GEOMETRY)
        self._geometry_seq = -1
        self.model = model or WorldModel()
        self._params: StationParams | None = None
        #: every world written (the station records it)
        self.on_world: Callable[[WorldState], None] = lambda w: None
        self.latency = LatencyStage()  # relay arrival -> world written
        #: per robot (team, id): the relay's receive stamp of the newest merged frame with a
        #: detection of it (the command publisher's frame age: what the robot experiences)
        self.arrivals: dict[tuple[Team, int], int] = {}
        #: every detection frame's arrival, merged or not (a camera whose frames are dropped
        #: is not silent: that is the stale world's stop); the control's all-vision-lost stop
        self.silence = CameraSilence(self.model.config.max_camera_id)
        self._rejected_total = 0
        # (monotonic time, counts by reason) when the counts changed, the last 10 s
        self._rejection_log: deque[tuple[float, dict[str, int]]] = deque(maxlen=32)

    def recent_rejections(self, window_s: float = 10.0) -> dict[str, int]:
        """What the world model dropped in the last ``window_s``, by reason."""
        now = time.monotonic()
        base: dict[str, int] | None = None
        for t, counts in self._rejection_log:
            if now - t > window_s:
                base = counts
        cur = self.model.rejected
        if not self._rejection_log or now - self._rejection_log[-1][0] > window_s:
            return {}
        base = base or {}
        return {k: v - base.get(k, 0) for k, v in sorted(cur.items()) if v - base.get(k, 0) > 0}

    def _field_from_geometry(self) -> None:
        if self.geometry.seq == self._geometry_seq:
            return
        self._geometry_seq = self.geometry.seq
        g = self.geometry.latest_value()
        if g is not None:
            self.model.set_field(g["field_length"] / 2, g["field_width"] / 2,
                                 g["boundary_width"])
            # the cameras' positions: a chipped ball's height from where they see it
            self.model.set_cameras({c["id"]: (c["x"], c["y"], c["z"])
                                    for c in g.get("cameras", ())})

    def reset(self) -> None:
        """A fresh world model (time jumped: a replay was opened or seeked, or went live),
        configured as the old one and told the field again."""
        self.reader.read_new()  # frames of before the jump are not merged
        self.model = WorldModel()
        self.silence.reset()
        self.arrivals.clear()  # (cleared, not replaced: the publisher holds it)
        if self._params is not None:
            self.configure(self._params)
        self._geometry_seq = -1

    def configure(self, params: StationParams) -> None:
        self._params = params
        w, wc = params.world, self.model.config
        wc.merge_window_s = w.merge_window_s
        wc.predict_after_s = w.predict_after_s
        wc.visible_timeout_s = w.visible_timeout_s
        wc.drop_timeout_s = w.drop_timeout_s
        k, kc = params.kicks, self.model.kicks.config
        self.model.kicks_enabled = k.enabled
        kc.decel_mps2, kc.jump_mps, kc.jump_window_s = k.decel_mps2, k.jump_mps, k.jump_window_s
        kc.reach_mm, kc.front_half_angle_deg = k.reach_mm, k.front_half_angle_deg
        kc.stop_mps, kc.max_turn_deg, kc.fit_window_s = k.stop_mps, k.max_turn_deg, k.fit_window_s
        fc = self.model.flight.config
        fc.enabled, fc.restitution = k.chips, k.chip_restitution
        fc.decel_mm_s2 = k.decel_mps2 * 1000.0
        self.model.configure(params.filters)

    def step(self) -> None:
        missed = self.reader.missed
        frames = self.reader.read_new()
        if self.reader.missed > missed:  # overwritten before merged: counted, like the ingest's
            n = self.reader.missed - missed
            self.model.rejected[streams.BEHIND] = self.model.rejected.get(streams.BEHIND, 0) + n
            badlog.warning("world-behind", "world model behind: %d camera frame(s) not merged",
                           n)
        if not frames:
            return
        heard = self.silence.frame
        for f in frames:
            heard(f.camera_id, f.receive_time_ns)
        self._field_from_geometry()
        merged = [f for f in frames if self.model.update(f)]
        total = sum(self.model.rejected.values())
        if total != self._rejected_total:
            self._rejected_total = total
            now, log_ = time.monotonic(), self._rejection_log
            if log_ and now - log_[-1][0] < 1.0:  # one entry a second at most
                log_[-1] = (log_[-1][0], dict(self.model.rejected))
            else:
                log_.append((now, dict(self.model.rejected)))
            badlog.warning("world-rejected", "vision dropped by the world model (%s so far): "
                            "%s", _reasons(self.model.rejected), self.model.last_rejection)
        if not merged:
            return
        world = self.model.snapshot()
        self.world.write(world)
        self.on_world(world)
        now_ns, add_at = time.time_ns(), self.latency.add_at  # (one clock read for the lot)
        arrivals = self.arrivals
        for f in merged:
            recv_ns = f.receive_time_ns
            add_at(now_ns, recv_ns)
            for r in f.robots:  # (in arrival order: the newest frame's stamp stays)
                arrivals[(r.team, r.id)] = recv_ns


def _reasons(counts: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
