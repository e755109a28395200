"""A regression test of the world model on real records: a 2.5 s session of the built-in
simulator recorded by the station (tests/data/fieldsim-2s.log.gz: the vision datagrams as
received, and the world estimate the live station made of each tick, as tracked vision).

Re-running today's world model over the recorded vision must give the estimates the live
station gave, once the filters have settled (the file starts in the middle of a session).
A failure means the world model's behaviour changed: if on purpose, record a new file (see
the docstring of ``test_replayed_world_matches_the_live_estimate``)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from backend.world.decode import decode_detection, geometry_to_dict
from backend.world.model import WorldModel
from ssllog.format import TYPE_TRACKER_2020, TYPE_VISION_2014
from ssllog.logfile import LogFile
from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket

FIXTURE = Path(__file__).resolve().parents[2] / "data" / "fieldsim-2s.log.gz"
SETTLE_S = 1.0  # the filters' state before the file began is not in it


def _key(team: int, rid: int) -> tuple[str, int]:
    return ("yellow" if team == 1 else "blue", rid)


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> LogFile:
    return LogFile.open(str(FIXTURE), tmp_path_factory.mktemp("cache"))


def test_fixture_is_what_the_station_records(log: LogFile) -> None:
    """Vision from four cameras, the referee, the world of each tick, the commands sent and
    the operator's actions (STOP, FORCE_START, a target)."""
    c = log.counts
    assert c[TYPE_VISION_2014] > 500 and c[TYPE_TRACKER_2020] > 400 and c[3] > 20
    assert c[1001] > 400 and c[1003] == 3 and c[1005] == 1
    assert sorted(log.cameras) == [0, 1, 2, 3]
    labels = [e.label for e in log.events if e.kind == "command"]
    assert "STOP" in labels and "FORCE_START" in labels


def test_replayed_world_matches_the_live_estimate(log: LogFile) -> None:
    """To record a new fixture: ``python -m launcher --isolated --record-dir DIR
    --backend-arg=--set=recording.rotate_on_stage=false``, POST /api/recording new-file,
    give STOP, FORCE_START and a target, new-file again; gzip the middle file."""
    # the fixture was recorded when the default filter was Kalman: replay with that one
    from backend.filters.params import FilterSettings

    model = WorldModel(filters=FilterSettings(robot="kalman", ball="kalman"))
    compared = 0
    worst = 0.0
    t0 = log.t_first_ns
    last_recv = 0
    for rec in log.records():
        if rec.type == TYPE_VISION_2014:
            pkt = SSL_WrapperPacket()
            pkt.ParseFromString(rec.payload)
            if pkt.HasField("geometry"):
                g = geometry_to_dict(pkt.geometry)
                model.set_field(g["field_length"] / 2, g["field_width"] / 2,
                                g["boundary_width"])
            if pkt.HasField("detection"):
                model.update(decode_detection(pkt.detection, rec.time_ns))
                last_recv = rec.time_ns
        elif rec.type == TYPE_TRACKER_2020 and rec.time_ns == last_recv:
            if (rec.time_ns - t0) / 1e9 < SETTLE_S:
                continue
            live = TrackerWrapperPacket()
            live.ParseFromString(rec.payload)
            now = model.snapshot()
            assert now.t_capture == pytest.approx(live.tracked_frame.timestamp, abs=1e-6)
            ours = {(r.team, r.id): r for r in now.robots}
            for tr in live.tracked_frame.robots:
                r = ours[_key(tr.robot_id.team, tr.robot_id.id)]
                d = math.hypot(r.x - tr.pos.x * 1000, r.y - tr.pos.y * 1000)
                worst = max(worst, d)
            compared += 1
    assert compared > 200, "too few ticks compared: the fixture or the matching changed"
    assert worst < 1.0, f"replayed robots differ from the live estimate by up to {worst:.2f} mm"


def test_history_is_the_world_model_over_the_log_before_the_playhead(log: LogFile) -> None:
    """GET /api/player/history's core: 30 samples a second of log up to the playhead, in
    order, each the estimate of that time (close to what the live station estimated)."""
    from backend.filters.params import FilterSettings
    from backend.replay.history import history

    end = log.t_first_ns + int(2.0 * 1e9)
    samples = history(log, end, 1.0, FilterSettings())
    times = [s["t_unix"] for s in samples]
    assert times == sorted(times)
    assert end / 1e9 - 1.0 <= times[0] < end / 1e9 - 0.9 and times[-1] <= end / 1e9
    assert 25 <= len(samples) <= 31
    live: dict[int, TrackerWrapperPacket] = {}
    for rec in log.records():
        if rec.type == TYPE_TRACKER_2020:
            p = TrackerWrapperPacket()
            p.ParseFromString(rec.payload)
            live[rec.time_ns] = p
    last = samples[-1]
    tracked = live[round(last["t_unix"] * 1e9)] if round(last["t_unix"] * 1e9) in live else \
        live[max(t for t in live if t <= end)]
    ours = {(r["team"], r["id"]): r for r in last["world"]["robots"]}
    assert len(ours) == len(tracked.tracked_frame.robots)
    for tr in tracked.tracked_frame.robots:
        r = ours[_key(tr.robot_id.team, tr.robot_id.id)]
        assert math.hypot(r["x"] - tr.pos.x * 1000, r["y"] - tr.pos.y * 1000) < 20
