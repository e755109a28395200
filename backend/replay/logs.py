"""Which logs the page may open, and opening one for the player.

The page names a file by path; only files inside the recording folder and the folders given
with ``--log-dir`` are opened (a browser must not make the station read any file it likes).
Indexes and decompressed copies go into a cache folder beside the recordings, never beside
the user's file.
"""

from __future__ import annotations

import os
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
        files: list[contract.LogFileInfo] = []
        for folder in self.folders():
            if not folder.is_dir():
                continue
            for entry in os.scandir(folder):
                if not entry.name.endswith(LOG_SUFFIXES) or not entry.is_file():
                    continue
                st = entry.stat()
                files.append({"name": entry.name, "path": str(Path(entry.path).resolve()),
                              "size_bytes": st.st_size, "modified_unix": st.st_mtime})
        files.sort(key=lambda f: f["modified_unix"], reverse=True)
        return {"folders": [str(f) for f in self.folders()], "files": files[:MAX_LISTED]}


def open_log_file(path: str, cache_dir: Path,
                  progress: Callable[[float], None] | None = None) -> LogSource:
    """Opens (and on first use indexes) a log for the player; slow: run in a worker thread."""
    from ssllog.logfile import LogFile

    cache_dir.mkdir(parents=True, exist_ok=True)
    log: LogSource = LogFile.open(path, cache_dir, progress)
    return log
