"""All vision lost through the real processes (issue 30, item 3): the launcher's relay and
backend with no simulator; this program is the camera (real SSL_WrapperPacket multicast at
60 Hz) and the simulator (the relay's RobotControl datagrams, stamped by the kernel on
arrival). Blue 0 is driven; the camera falls silent: the relay's output commands zero to
every robot within 100 ms of the last frame (it was 305-311 ms with vision_stale_s alone),
the station says why in halt_reason and in its health, and until the relay's next statistics
it sent nothing else. Heard again, the robots drive."""

from __future__ import annotations

import httpx

from .blind import Camera, Simulator
from .conftest import StationHandle, arm, next_relay_stats, wait_until

BOUND_NS = 100_000_000  # the bound: last frame -> zero leaves the relay


def test_every_camera_silent_stops_every_robot_within_100_ms(bare: StationHandle) -> None:
    p = bare.ports
    sim = Simulator(p["sim_blue"])
    cam = Camera(p["vision_group"], p["vision"])
    try:
        wait_until(lambda: any(r["id"] == 0 for r in bare.get("/api/world")["robots"]), 20,
                   what="blue 0 seen")
        wait_until(lambda: bare.get("/api/health")["relay"], 10, what="relay statistics")
        arm(bare)  # an external simulator: the station starts disarmed
        r = httpx.post(bare.url + "/api/robots/blue/0/target", json={"x": 3000.0, "y": 0.0},
                       timeout=5)
        assert r.status_code == 200, r.text
        wait_until(sim.driving, 10, what="blue 0 commanded to drive")
        # the camera's rate measured: the station stops after 80 ms of silence
        world = wait_until(lambda: (w := bare.get("/api/health")["world"])["lost_after_s"]
                           is not None and w, 10, what="the camera's rate measured")
        # (this program's pacing on a loaded machine: about 60 Hz; 6 periods, at most
        # 100 ms, less 20 ms: 80 ms, a little less when frames came faster than 60 Hz)
        assert world["camera_rates_hz"]["0"] >= 30.0, world
        assert 0.05 <= world["lost_after_s"] <= 0.08 + 1e-9, world

        sim.read()  # what came before
        last_ns = cam.silence()
        stop, drove = sim.stop_after(last_ns)
        took_ns = stop.arrival_ns - last_ns
        # (the last frame's send time is before the relay received it, the stop's arrival
        # after the relay sent it: the relay's own interval is shorter still)
        assert took_ns < BOUND_NS, (f"stopped {took_ns / 1e6:.1f} ms after the last frame: "
                                    + sim.describe(last_ns))
        # driven on the last commands until the station's stop (the relay's own stale stop
        # comes 100 ms after the last command, which came after the last frame: not it)
        assert drove is not None and drove.arrival_ns > last_ns, \
            "blue 0 was not driving after the last frame: something else stopped it"

        w = bare.get("/api/world")
        assert w["halt_reason"].startswith("no vision: every camera silent for "), w["halt_reason"]
        assert w["halt_reason"].endswith(" Hz)")
        # the relay's statistics stamped after this: every datagram it sent before is here
        h = next_relay_stats(bare)
        assert not h["ok"]
        assert h["world"]["stale"] and h["world"]["vision_lost"].startswith(
            "no vision: every camera silent for "), h["world"]
        assert any(x.startswith("no vision: every camera silent for ") and
                   x.endswith(": robots stopped") for x in h["warnings"]), h["warnings"]
        later = sim.read()
        assert later and all(s == 0.0 for c in later for s in c.speeds.values())

        cam.resume()
        wait_until(sim.driving, 10, what="blue 0 driving again with vision back")
        assert bare.get("/api/world")["halt_reason"] == ""
    finally:
        cam.close()
        sim.close()
