"""The station indexes a log in a child process (backend.replay.logs.index_log): progress
from it, its error as the player's, the child ended when the open is cancelled, and the log
then opened from the cache without a scan in the station's process."""

from __future__ import annotations

import asyncio
import os
from pathlib import Path

import pytest

from backend.replay.logs import index_log, open_indexed
from backend.replay.player import PlayerError
from ssllog import logfile
from tests.ssllog.test_logfile import vision_log


async def test_indexed_in_a_child_then_opened_from_the_cache(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    p = tmp_path / "m.log"
    p.write_bytes(vision_log(5000))
    seen: list[float] = []
    await index_log(str(p), tmp_path / "cache", seen.append)
    assert seen and seen == sorted(seen) and seen[-1] == 1.0

    def no_scan(*a: object, **k: object) -> None:
        raise AssertionError("the index pass ran in the station's process")

    monkeypatch.setattr(logfile, "build_index", no_scan)
    log = open_indexed(str(p), tmp_path / "cache")
    try:
        assert log.t_last_ns > log.t_first_ns
    finally:
        log.close()
    # a file changed after its indexing is refused, not indexed here
    p.write_bytes(vision_log(6000))
    with pytest.raises(PlayerError, match="changed while it was indexed"):
        open_indexed(str(p), tmp_path / "cache")


async def test_a_bad_file_is_the_childs_one_line_reason(tmp_path: Path) -> None:
    p = tmp_path / "bad.log"
    p.write_bytes(b"garbage garbage garbage")
    with pytest.raises(PlayerError) as err:
        await index_log(str(p), tmp_path / "cache")
    assert str(err.value).startswith("corrupt SSL log at byte 0"), str(err.value)


async def test_cancelled_open_ends_the_child(tmp_path: Path) -> None:
    """The station stops (or the open is abandoned) while a big log is indexed: the child
    does not run on."""
    p = tmp_path / "big.log"
    p.write_bytes(vision_log(400_000))
    # children of this process from before (a pool's forkserver an earlier test left) are not
    # the indexer's
    before = set(_children())
    started = asyncio.Event()
    task = asyncio.create_task(index_log(str(p), tmp_path / "cache",
                                         lambda f: started.set()))
    await asyncio.wait_for(started.wait(), 30)
    children = set(_children()) - before
    assert children, "no indexing process"
    task.cancel()
    with pytest.raises(asyncio.CancelledError):
        await task
    for pid in children:  # killed and reaped by the cancelled call
        assert not Path(f"/proc/{pid}").exists() or _state(pid) == "Z"


def _children() -> list[int]:
    me = os.getpid()
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == me:
                out.append(int(d.name))
    return out


def _state(pid: int) -> str:
    try:
        return (Path(f"/proc/{pid}") / "stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "gone"
