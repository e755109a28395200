"""The relay ingest waits on its ZeroMQ socket's descriptor (watched once, not a poll per
wake-up): every message published wakes it, also one that came while it was draining."""

from __future__ import annotations

import asyncio

import zmq
import zmq.asyncio

from backend import topics
from backend.bus import DataBus, Reader
from backend.processor import OnTopic, Processor, Runner
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


class Collect(Processor):
    """Reads the vision packets topic in the pass, like the vision ingest."""

    name = "collect"

    def __init__(self, bus: DataBus) -> None:
        packets = bus.of(topics.VISION_PACKETS)
        super().__init__(OnTopic(packets))
        self.reader = Reader(packets)
        self.seqs: list[int] = []
        self.tasks: set[str] = set()

    def step(self) -> None:
        for env in self.reader.read_new():
            self.seqs.append(env.sequence)
            task = asyncio.current_task()
            self.tasks.add(task.get_name() if task else "")


async def test_in_the_runner_the_descriptor_ticks_the_ingest_and_a_burst_is_never_lost() -> None:
    """Watched by the runner (``watch_input``), the ingest is ticked with its pass inside
    the descriptor's callback (no task). A burst larger than the vision topic is taken a
    topic's worth a pass, the rest in the loop's next turns: nothing is overwritten unread,
    although the descriptor signals the burst only once."""
    ctx = zmq.asyncio.Context()
    pub = ctx.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    bus = DataBus({"vision-packets": 4})
    ingest = RelayIngest(bus, sub_socket(ctx, f"tcp://127.0.0.1:{port}", [b"vision"]))
    collect = Collect(bus)
    runner = Runner()
    runner.add(ingest)
    runner.add(collect)
    await runner.start()
    try:
        assert not any(t.get_name() == ingest.name for t in asyncio.all_tasks())
        seq = 0
        for _ in range(500):  # the subscription joins: publish until one arrives (bounded)
            seq += 1
            pub.send_multipart([b"vision", envelope(seq)])
            await asyncio.sleep(0.01)
            if collect.seqs:
                break
        first = seq + 1
        for k in range(first, first + 25):  # one burst, six times the topic's capacity
            pub.send_multipart([b"vision", envelope(k)])
        for _ in range(500):  # bounded
            await asyncio.sleep(0.01)
            if collect.seqs and collect.seqs[-1] == first + 24:
                break
    finally:
        await runner.stop()
        ctx.destroy(linger=0)
    assert collect.seqs[-25:] == list(range(first, first + 25))
    assert ingest.stats.rate.total >= 7  # at most 4 a tick
    assert collect.tasks == {""}
