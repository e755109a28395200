"""The plots' past after a seek: the world model re-run over the stretch of log before the
playhead, off the station thread, sampled for the page's plots.

A seek restarts the station's world model at the new position, so the live stream has no past
to show; the page asks for it once (GET /api/player/history) and fills its plot window. The
history is the world model's estimate (positions, orientations, velocities, the ball) with the
filters in force; what only the control loop computes (controller telemetry) starts at the
seek."""

from __future__ import annotations

from google.protobuf.message import DecodeError

from ssllog.format import TYPE_VISION_2014
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

from .. import contract
from ..filters.params import FilterSettings
from ..world.decode import decode_detection, geometry_to_dict
from ..world.model import WorldModel
from ..world.state import WorldState
from .player import PREROLL_S, LogSource

#: samples per second of log (the page plots at most 60 rows a second of live data)
HISTORY_HZ = 30.0


def history(log: LogSource, end_ns: int, seconds: float, filters: FilterSettings,
            hz: float = HISTORY_HZ) -> list[contract.HistorySample]:
    """The world estimate every 1/hz s of log time over ``seconds`` before ``end_ns`` (the
    filters settle over the pre-roll before the first sample)."""
    start_ns = max(log.t_first_ns, end_ns - int(seconds * 1e9))
    model = WorldModel()
    model.configure(filters)
    out: list[contract.HistorySample] = []
    step_ns = int(1e9 / hz)
    next_ns = start_ns
    from_ns = max(log.t_first_ns, start_ns - int(PREROLL_S * 1e9))
    for rec in log.records(log.offset_at(from_ns)):
        if rec.time_ns > end_ns:
            break
        if rec.type != TYPE_VISION_2014:
            continue
        pkt = SSL_WrapperPacket()
        try:
            pkt.ParseFromString(rec.payload)
        except DecodeError:
            continue
        if not merge_wrapper(model, pkt, rec.time_ns):
            continue
        if rec.time_ns >= next_ns:
            next_ns = max(next_ns + step_ns, rec.time_ns)
            out.append({"t_unix": rec.time_ns / 1e9, "world": _sample(model.snapshot())})
    return out


def merge_wrapper(model: WorldModel, pkt: SSL_WrapperPacket, receive_time_ns: int) -> bool:
    """One vision datagram into ``model`` as the station's ingest and world processor do
    (the field from a geometry packet, the detection merged); True if a frame was merged."""
    if pkt.HasField("geometry"):
        g = geometry_to_dict(pkt.geometry)
        model.set_field(g["field_length"] / 2, g["field_width"] / 2, g["boundary_width"])
        model.set_cameras({c["id"]: (c["x"], c["y"], c["z"]) for c in g["cameras"]})
    return pkt.HasField("detection") and model.update(
        decode_detection(pkt.detection, receive_time_ns))


def _sample(w: WorldState) -> contract.HistoryWorld:
    b = w.ball
    return {
        "ball": None if b is None else {"x": b.x, "y": b.y, "vx": b.vx, "vy": b.vy},
        "robots": [{"team": r.team, "id": r.id, "x": r.x, "y": r.y,
                    "orientation": r.orientation, "vx": r.vx, "vy": r.vy, "omega": r.omega}
                   for r in w.robots if r.visible],
    }
