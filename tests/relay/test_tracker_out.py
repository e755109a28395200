"""The station's tracked vision ("tracker-out"): checked, counted by reason, multicast on
loopback only unless --tracker-out with a non-loopback --interface."""

from __future__ import annotations

import asyncio
import socket

import pytest

from larcmacs_relay import RelayConfig
from larcmacs_relay.__main__ import build_parser, config_from_args
from sslnet import streams
from sslnet.multicast import open_multicast_receiver
from sslpb import touchline_pb2
from sslpb.ssl_gc_common_pb2 import BLUE
from sslpb.ssl_vision_wrapper_tracked_pb2 import TrackerWrapperPacket
from tests.relay.conftest import running_relay, subscribed
from tests.waiting import until


def tracked(frame: int, uuid: str = "0123abcd", robots: int = 2) -> bytes:
    p = TrackerWrapperPacket(uuid=uuid, source_name="Touchline")
    p.tracked_frame.frame_number = frame
    p.tracked_frame.timestamp = 1.7e9 + frame / 60
    for i in range(robots):
        r = p.tracked_frame.robots.add(orientation=0.5, visibility=1.0)
        r.robot_id.id, r.robot_id.team = i, BLUE
        r.pos.x, r.pos.y = 0.1 * i, -0.2
    return p.SerializeToString()


async def recv(sock: socket.socket, timeout: float = 2.0) -> bytes:
    return await asyncio.wait_for(asyncio.get_running_loop().sock_recv(sock, 65536), timeout)


async def test_tracked_vision_is_sent_and_bad_bytes_are_counted_by_reason() -> None:
    async with running_relay() as h:
        cfg = h.config
        assert cfg.tracker_out_interface == "127.0.0.1"
        listener = open_multicast_receiver(cfg.tracker_out_group, cfg.tracker_out_port,
                                           "127.0.0.1")
        pub = h.publisher()
        counter = h.relay.streams["tracker_out"]
        try:
            # ZeroMQ slow joiner: send until the first one is on the wire
            first = tracked(1)
            deadline = asyncio.get_running_loop().time() + 3.0
            while counter.packets == 0:
                assert asyncio.get_running_loop().time() < deadline, "relay never got one"
                await pub.send_multipart([b"tracker-out", first])
                await asyncio.sleep(0.02)
            assert await recv(listener) == first
            while True:  # the probes' copies
                try:
                    listener.recv(65536)
                except BlockingIOError:
                    break
            sent = counter.packets
            full = tracked(2)
            no_frame = TrackerWrapperPacket(uuid="x", source_name="s").SerializeToString()
            no_uuid = TrackerWrapperPacket(uuid="").SerializeToString() + b"\x1a\x00"
            missing = b"\x0a\x01x\x1a\x02\x08\x01"  # tracked_frame without its timestamp
            bad = {
                full[:-3]: streams.TRUNCATED,
                b"\x0f\x01": streams.NOT_PROTOBUF,
                b"": streams.NO_CONTENT,
                no_frame: streams.NO_CONTENT,
                missing: streams.MISSING_FIELD,
                no_uuid: streams.MISSING_FIELD,
            }
            for body in bad:
                await pub.send_multipart([b"tracker-out", body])
            await pub.send_multipart([b"tracker-out", full])
            assert await recv(listener) == full  # the bad ones never went out
            await until(lambda: counter.errors == len(bad), what="tracker-out errors")
            assert counter.packets == sent + 1
            expected: dict[str, int] = {}
            for kind in bad.values():
                expected[kind] = expected.get(kind, 0) + 1
            assert counter.by_reason == expected
            with pytest.raises(BlockingIOError):
                listener.recv(65536)
            # and it is in the relay's stats
            stats = {s.name: s for s in h.relay.stats().streams}
            assert stats["tracker_out"].packets == sent + 1
            assert dict(stats["tracker_out"].errors_by_reason) == expected
        finally:
            listener.close()


async def test_loopback_output_has_ttl_zero() -> None:
    async with running_relay() as h:
        tout = h.relay._tracker_out
        assert tout is not None
        assert tout.getsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL) == 0
        iface = tout.getsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_IF, 4)
        assert socket.inet_ntoa(iface) == "127.0.0.1"


async def test_own_frames_heard_back_on_the_tracker_input_are_not_forwarded() -> None:
    """With the tracker input on the same group and port (loopback), the relay hears its own
    tracked vision: it is not taken for another tracker's."""
    from tests.ports import random_multicast_port

    port = random_multicast_port()
    async with running_relay(tracker_enabled=True, tracker_port=port,
                             tracker_out_port=port) as h:
        sub = h.subscriber(b"tracker")
        pub = h.publisher()
        other = tracked(9, uuid="other-tracker")
        dest = (h.config.tracker_group, port)
        _, body = await subscribed(sub, lambda: h.sender.sendto(other, dest))
        assert touchline_pb2.Envelope.FromString(body).payload == other
        counter = h.relay.streams["tracker_out"]
        while counter.packets == 0:
            await pub.send_multipart([b"tracker-out", tracked(1)])
            await asyncio.sleep(0.02)
        await until(lambda: h.relay.own_tracker_echoes >= counter.packets >= 1,
                       what="every own frame heard back")
        # another tracker's frame after them: the relay forwards in order on its one PUB, so
        # an echo forwarded by mistake comes before this marker (no waiting for quiet)
        h.sender.sendto(tracked(99, uuid="other-tracker"), dest)
        while True:
            env = touchline_pb2.Envelope.FromString(
                (await asyncio.wait_for(sub.recv_multipart(), 3.0))[1])
            got = TrackerWrapperPacket.FromString(env.payload)
            assert got.uuid == "other-tracker"
            if got.tracked_frame.frame_number == 99:
                break


async def test_no_tracker_out_refuses_and_counts() -> None:
    async with running_relay(tracker_out=False) as h:
        pub = h.publisher()
        counter = h.relay.streams["tracker_out"]
        while counter.errors == 0:
            await pub.send_multipart([b"tracker-out", tracked(1)])
            await asyncio.sleep(0.02)
        assert counter.packets == 0 and "output off" in counter.by_reason


def test_lan_only_when_asked_for() -> None:
    def cfg(*argv: str) -> RelayConfig:
        c = config_from_args(build_parser().parse_args(list(argv)))
        c.validate()
        return c

    c = cfg()
    assert (c.tracker_out, c.tracker_out_interface) == (True, "127.0.0.1")
    assert (c.tracker_out_group, c.tracker_out_port) == ("224.5.23.2", 10010)
    # a venue interface alone does not put tracked vision on the venue network
    c = cfg("--interface", "192.0.2.2")
    assert c.tracker_out_interface == "127.0.0.1" and c.tracker_out_on_loopback
    c = cfg("--interface", "192.0.2.2", "--tracker-out-local", "224.5.23.2:31000")
    assert (c.tracker_out_interface, c.tracker_out_port) == ("127.0.0.1", 31000)
    c = cfg("--interface", "192.0.2.2", "--tracker-out", "224.5.23.2:10010")
    assert c.tracker_out_interface == "192.0.2.2" and not c.tracker_out_on_loopback
    c = cfg("--tracker-out", "224.5.23.2:10011")  # asked for, but the interface is loopback
    assert c.tracker_out_interface == "127.0.0.1" and c.tracker_out_port == 10011
    assert not cfg("--no-tracker-out").tracker_out
    assert "loopback" in build_parser().format_help()
