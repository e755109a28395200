"""The station's world estimate as the league's tracked vision, through the real processes:
the relay multicasts it on loopback (the isolated tracker port) at the world rate up to
tracker.max_hz, with one
uuid, frame numbers increasing and robots where GET /api/world has them; nothing while a log
is replayed, and again once live."""

from __future__ import annotations

import itertools
import select
import threading
import time
from pathlib import Path
from typing import Any

import httpx

from domain.angles import wrap_angle
from sslnet.multicast import open_multicast_receiver
from sslpb.ssl_gc_common_pb2 import BLUE, YELLOW
from sslpb.ssl_vision_detection_tracked_pb2 import (
    CAPABILITY_DETECT_FLYING_BALLS,
    CAPABILITY_DETECT_MULTIPLE_BALLS,
)
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket

from .conftest import StationHandle, launched, next_relay_stats, wait_until

FIXTURE = Path(__file__).resolve().parents[1] / "data" / "fieldsim-2s.log.gz"


class Listener:
    """Every tracked frame on the station's tracker group and port (joined on 127.0.0.1),
    with its arrival time (monotonic), in a thread."""

    def __init__(self, group: str, port: int) -> None:
        self.sock = open_multicast_receiver(group, port, "127.0.0.1")
        self.frames: list[tuple[float, TrackerWrapperPacket]] = []
        self.bad = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            ready, _, _ = select.select([self.sock], [], [], 0.1)
            if not ready:
                continue
            while True:
                try:
                    data = self.sock.recv(65536)
                except BlockingIOError:
                    break
                p = TrackerWrapperPacket()
                try:
                    p.ParseFromString(data)
                except Exception:
                    self.bad += 1
                    continue
                if not p.IsInitialized():
                    self.bad += 1
                    continue
                self.frames.append((time.monotonic(), p))

    def since(self, t: float) -> list[TrackerWrapperPacket]:
        return [p for at, p in list(self.frames) if at >= t]

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        self.sock.close()


def world_seq(st: StationHandle) -> int:
    return next(t["seq"] for t in st.get("/api/health")["topics"] if t["name"] == "world")


def player(st: StationHandle, body: dict[str, Any]) -> dict[str, Any]:
    r = httpx.post(st.url + "/api/player", json=body, timeout=10.0)
    assert r.status_code == 200, r.text
    return r.json()  # type: ignore[no-any-return]


def test_tracked_vision_on_loopback_and_silent_in_replay() -> None:
    with launched("--log-dir", str(FIXTURE.parent)) as st:
        ports = st.ports
        assert ports["tracker"] != 10010
        rx = Listener(ports["tracker_group"], ports["tracker"])
        try:
            wait_until(lambda: len(st.get("/api/world")["robots"]) >= 6, 20, what="robots")
            wait_until(lambda: len(rx.frames) > 20, 10, what="tracked frames")

            # about the world rate up to tracker.max_hz (100): the newest world, 10 ms of
            # capture time apart at least (counted over ~2 s)
            t0, seq0 = time.monotonic(), world_seq(st)
            time.sleep(2.0)
            t1, seq1 = time.monotonic(), world_seq(st)
            time.sleep(0.2)  # the last ones on their way
            got = [p for at, p in list(rx.frames) if t0 <= at <= t1 + 0.2]
            worlds = seq1 - seq0
            assert worlds > 60, worlds  # fieldsim: > 30 Hz of worlds
            expected = min(worlds, 100.0 * (t1 - t0))
            # a frame waits for the first world 10 ms after the last one sent: worlds just under
            # 10 ms apart send every other one (50 Hz, half the expected; a CI run saw 61 Hz of
            # 101 Hz of worlds), worlds further apart send each one
            assert 0.45 * expected <= len(got) <= 1.1 * expected, (len(got), worlds, expected)

            frames = [p for _, p in list(rx.frames)]
            assert rx.bad == 0
            assert len({p.uuid for p in frames}) == 1 and frames[0].uuid
            assert {p.source_name for p in frames} == {"Touchline"}
            numbers = [p.tracked_frame.frame_number for p in frames]
            assert all(b > a for a, b in itertools.pairwise(numbers)), numbers[:50]
            # capabilities: flying balls (fieldsim sends its cameras' positions); no second
            # ball on this field; a kick only while one runs (none without a play)
            assert all(CAPABILITY_DETECT_FLYING_BALLS in p.tracked_frame.capabilities
                       and CAPABILITY_DETECT_MULTIPLE_BALLS not in p.tracked_frame.capabilities
                       for p in frames[-20:])

            # robots in metres where the world has them (the frame of the same capture time)
            def matched() -> tuple[dict[str, Any], TrackerWrapperPacket] | None:
                w = st.get("/api/world")
                for p in reversed([p for _, p in list(rx.frames)]):
                    if abs(p.tracked_frame.timestamp - w["t_capture"]) < 1e-6:
                        return w, p
                return None

            w, p = wait_until(matched, 10, what="a tracked frame of the world's capture time")
            team = {YELLOW: "yellow", BLUE: "blue"}
            tracked = {(team[r.robot_id.team], r.robot_id.id): r for r in p.tracked_frame.robots}
            assert len(tracked) == len(w["robots"]) >= 6
            for r in w["robots"]:
                t = tracked[(r["team"], r["id"])]
                assert abs(t.pos.x * 1000 - r["x"]) < 20 and abs(t.pos.y * 1000 - r["y"]) < 20
                # the same heading, whichever side of +-pi each is written on
                assert abs(wrap_angle(t.orientation - r["orientation"])) < 0.01
            if w["ball"] is not None:
                b = p.tracked_frame.balls[0]
                assert abs(b.pos.x * 1000 - w["ball"]["x"]) < 20

            # the relay counts what it sent
            relay_out = st.get("/api/health")["streams"]["relay.tracker_out"]
            assert relay_out["packets"] > 100 and relay_out["errors"] == 0, relay_out

            # replaying a log: nothing is published
            uuid, last_live = frames[0].uuid, numbers[-1]
            player(st, {"action": "open", "path": str(FIXTURE)})
            wait_until(lambda: st.get("/api/player")["source"] == "log", 20, what="log open")
            player(st, {"action": "play", "speed": 1})
            # the relay's own count of tracked frames sent, from statistics it stamped 0.3 s
            # after the play (frames already on their way when the log opened are in it)
            sent = next_relay_stats(st, 0.3)["streams"]["relay.tracker_out"]["packets"]
            t_replay = time.monotonic()
            wait_until(lambda: (st.get("/api/world")["replay"] or {}).get("position_s", 0) > 0.5,
                       10, what="the replay playing")
            # a second of the relay's time replaying: it sent none (its counter), and none
            # arrived here
            h = next_relay_stats(st, 1.0)
            assert h["streams"]["relay.tracker_out"]["packets"] == sent
            assert st.get("/api/world")["replay"] is not None
            assert rx.since(t_replay) == []

            # back to live: the same uuid, frame numbers go on
            player(st, {"action": "live"})
            t_live = time.monotonic()
            wait_until(lambda: len(rx.since(t_live)) > 20, 10, what="tracked frames again")
            again = rx.since(t_live)
            assert {p.uuid for p in again} == {uuid}
            assert again[0].tracked_frame.frame_number > last_live
        finally:
            rx.close()
