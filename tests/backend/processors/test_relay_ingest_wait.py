"""The relay ingest waits on its ZeroMQ socket's descriptor (watched once, not a poll per
wake-up): every message published wakes it, also one that came while it was draining."""

from __future__ import annotations

import asyncio

import zmq
import zmq.asyncio

from backend import topics
from backend.bus import DataBus
from backend.processors.relay_ingest import RelayIngest
from backend.zmqio import sub_socket
from sslpb import touchline_pb2 as tl


def envelope(seq: int) -> bytes:
    return tl.Envelope(stream=tl.STREAM_VISION, receive_time_ns=1, sequence=seq,
                       source="test", payload=b"x").SerializeToString()


async def test_every_message_wakes_the_ingest_and_teardown_unwatches() -> None:
    ctx = zmq.asyncio.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    bus = DataBus({})
    ingest = RelayIngest(bus, sub_socket(ctx, f"tcp://127.0.0.1:{port}", [b"vision"]))
    packets = bus.of(topics.VISION_PACKETS)
    try:
        seq = 0
        for _ in range(500):  # the subscription joins: publish until one arrives (bounded)
            seq += 1
            pub.send_multipart([b"vision", envelope(seq)])
            try:
                await asyncio.wait_for(ingest.wait_input(), 0.01)
                break
            except TimeoutError:
                continue
        await ingest.tick()
        assert packets.seq >= 1
        for _ in range(3):  # after a drain, a new message wakes it again
            before = packets.seq
            seq += 1
            pub.send_multipart([b"vision", envelope(seq)])
            await asyncio.wait_for(ingest.wait_input(), 5.0)
            await ingest.tick()
            assert packets.seq == before + 1
            assert packets.latest_value().sequence == seq  # type: ignore[union-attr]
        loop = asyncio.get_running_loop()
        fd = ingest._fd
        await ingest.teardown()
        assert not loop.remove_reader(fd)  # nothing left watching the descriptor
    finally:
        ctx.destroy(linger=0)
