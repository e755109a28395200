"""Which logs the page may open, and opening one for the player.

The page names a file by path; only files inside the recording folder and the folders given
with ``--log-dir`` are opened (a browser must not make the station read any file it likes).
Indexes and decompressed copies go into a cache folder beside the recordings, never beside
the user's file.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import sys
from collections.abc import Callable
from pathlib import Path

from .. import contract
from .player import LogSource, PlayerError

LOG_SUFFIXES = (".log", ".log.gz")
#: the files a listing shows at most (newest first)
MAX_LISTED = 500


class LogFolders:
    def __init__(self, recording_folder: Callable[[], Path], extra: list[Path]) -> None:
        self._recording_folder = recording_folder
        self._extra = [p.expanduser().resolve() for p in extra]

    def folders(self) -> list[Path]:
        return [self._recording_folder().expanduser().resolve(), *self._extra]

    def cache_dir(self) -> Path:
        return self._recording_folder().expanduser().resolve().parent / "log-cache"

    def check(self, path: str) -> str:
        """The real path of ``path`` if it is a log inside an allowed folder; else why not."""
        if "\0" in path:
            raise PlayerError("the path contains a NUL character")
        p = Path(path).expanduser()
        allowed = self.folders()
        if not p.is_absolute():  # a name in one of the folders (the first that has it)
            p = next((f / p for f in allowed if (f / p).exists()), allowed[0] / p)
        real = p.resolve()
        if not any(real.is_relative_to(f) for f in allowed):
            names = ", ".join(str(f) for f in allowed)
            raise PlayerError(f"{path} is not in a log folder ({names}); start the station with "
                              f"--log-dir to open logs from another folder")
        if not real.name.endswith(LOG_SUFFIXES):
            raise PlayerError(f"{path} is not a .log or .log.gz file")
        if not real.is_file():
            raise PlayerError(f"{path} does not exist")
        return str(real)

    def listing(self) -> contract.LogList:
        return list_logs(self.folders())


def list_logs(folders: list[Path]) -> contract.LogList:
    """The logs in ``folders``, newest first: a scan of the file system (a big or a network
    folder takes long), so the route runs it in a worker thread, not the station's."""
    files: list[contract.LogFileInfo] = []
    for folder in folders:
        if not folder.is_dir():
            continue
        for entry in os.scandir(folder):
            if not entry.name.endswith(LOG_SUFFIXES) or not entry.is_file():
                continue
            st = entry.stat()
            files.append({"name": entry.name, "path": str(Path(entry.path).resolve()),
                          "size_bytes": st.st_size, "modified_unix": st.st_mtime})
    files.sort(key=lambda f: f["modified_unix"], reverse=True)
    return {"folders": [str(f) for f in folders], "files": files[:MAX_LISTED]}


#: the indexing process's priority below the station's (it is background work: on a busy
#: machine the relay, the simulator and the station's own threads go first)
INDEX_NICE = 10
PROJECT_ROOT = Path(__file__).resolve().parents[2]


async def index_log(path: str, cache_dir: Path,
                    progress: Callable[[float], None] | None = None) -> None:
    """Builds the log's cache (a gzip copy, the index: one pass over the whole file) in a
    child process, ``python -m ssllog index``, at a lower priority. Not a thread: the pass
    is Python and C calls that hold the GIL (a large record's decode, a garbage collection
    of what it made), and every one of them would stop the station's pass and the tracked
    frames with it. Raises PlayerError with the child's message if it fails; a cancelled
    call ends the child."""
    cache_dir.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        x for x in (str(PROJECT_ROOT), env.get("PYTHONPATH", "")) if x)
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "ssllog", "--cache-dir", str(cache_dir), "index",
        "--progress-lines", path,
        stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE, env=env, cwd=str(PROJECT_ROOT),
        start_new_session=True)
    with contextlib.suppress(OSError):  # below the station from its first import on
        os.setpriority(os.PRIO_PROCESS, proc.pid, INDEX_NICE)
    assert proc.stdout is not None and proc.stderr is not None
    errors = asyncio.ensure_future(proc.stderr.read())
    try:
        async for raw in proc.stdout:
            word, _, value = raw.decode(errors="replace").partition(" ")
            if word == "progress" and progress is not None:
                with contextlib.suppress(ValueError):
                    progress(float(value))
        status = await proc.wait()
        said = (await errors).decode(errors="replace").strip()
    except BaseException:  # cancelled (the station stops, another open): no orphan
        with contextlib.suppress(ProcessLookupError):
            proc.kill()
        errors.cancel()
        await proc.wait()  # reaped before the caller goes on
        raise
    if status != 0:
        last = said.splitlines()[-1] if said else f"exit status {status}"
        raise PlayerError(last.removeprefix("ssllog: "))


def open_indexed(path: str, cache_dir: Path) -> LogSource:
    """Opens a log whose cache ``index_log`` has built (reads the index file: a worker
    thread's job, it is quick). A file changed since is refused, not indexed here."""
    from ssllog.logfile import LogFile, NotCached

    try:
        log: LogSource = LogFile.open(path, cache_dir, build=False)
    except NotCached as exc:
        raise PlayerError(f"{path} changed while it was indexed: open it again") from exc
    return log
