"""The log player's feed: the replayed records onto the ingest topics, on time."""

from __future__ import annotations

import asyncio
import contextlib

from ..processor import Processor
from ..replay.player import LogPlayer


class PlayerFeed(Processor):
    """Source processor: sleeps until the next record of the log is due (or a command woke
    it), then emits what is due, a batch at a time, so the processors reading the topics run
    between two batches and nothing is evicted unread."""

    name = "log-player"

    def __init__(self, player: LogPlayer) -> None:
        super().__init__(None)
        self.player = player
        self.wake = asyncio.Event()

    async def wait_input(self) -> None:
        wait = self.player.wait_s()
        if wait == 0.0:
            await asyncio.sleep(0)  # let the readers of the last batch run first
            return
        self.wake.clear()
        if wait is None:
            await self.wake.wait()
        else:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.wake.wait(), wait)

    async def tick(self) -> None:
        self.player.emit(self.player.due())
