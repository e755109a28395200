"""Reading and saving the team's files for the page (GET/PUT /api/team/files/{name}).

A save is atomic (a temporary file in the same folder, then a rename), refused when the file
changed on disk since the version the edit started from, and takes the same reload path as a
save from an editor (the watcher sees it; the route also asks for a scan at once)."""

from __future__ import annotations

import os
import tempfile
import threading
import time
from pathlib import Path

from .discovery import LIB, NAME_RE, Language, version_of

#: the largest file the page may save (UTF-8 bytes)
MAX_FILE_BYTES = 256 * 1024
_save_lock = threading.Lock()  # one save at a time: the version check and the rename together


class TeamFileError(Exception):
    """A refused read or save: the HTTP status and the reason."""

    def __init__(self, status: int, detail: str) -> None:
        super().__init__(detail)
        self.status = status
        self.detail = detail


def check_name(name: str) -> Language:
    if not NAME_RE.match(name):
        raise TeamFileError(422, f"{name!r} is not a team file name: x.py, x.m, lib/x.py or "
                                 "lib/x.m (x: a letter, then letters, digits or _)")
    return "python" if name.endswith(".py") else "octave"


def read(team_dir: Path, name: str) -> tuple[str, str, Language]:
    """(text, version, language) of a team file; 404 when there is none."""
    language = check_name(name)
    try:
        data = (team_dir / name).read_bytes()
    except FileNotFoundError:
        raise TeamFileError(404, f"no file {name} in the team folder {team_dir}") from None
    except OSError as exc:
        raise TeamFileError(409, f"{name} cannot be read: {exc.strerror}") from None
    return data.decode("utf-8", errors="replace"), version_of(data), language


def save(team_dir: Path, name: str, text: str, base_version: str | None) -> tuple[str, float]:
    """Writes ``text`` to the team file ``name`` atomically; returns (version, saved_at_unix).

    ``base_version``: the version the edit started from; the save is refused (409) when the
    file on disk is another one (changed meanwhile, or created when the caller made a new
    file: None), so nobody's work is overwritten unseen."""
    check_name(name)
    try:
        data = text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise TeamFileError(422, f"the text is not valid Unicode ({exc.reason})") from None
    if len(data) > MAX_FILE_BYTES:
        raise TeamFileError(413, f"{len(data)} bytes: a team file may have at most "
                                 f"{MAX_FILE_BYTES} bytes")
    if not team_dir.is_dir():
        raise TeamFileError(409, f"the team folder {team_dir} does not exist")
    path = team_dir / name
    with _save_lock:
        try:
            current: bytes | None = path.read_bytes()
        except FileNotFoundError:
            current = None
        except OSError as exc:
            raise TeamFileError(409, f"{name} cannot be read: {exc.strerror}") from None
        now = None if current is None else version_of(current)
        if now != base_version:
            if now is None:
                raise TeamFileError(409, f"{name} was deleted since version {base_version}")
            if base_version is None:
                # a script sees this one (the page opens an existing file): say how to save
                raise TeamFileError(409, f"{name} exists already (version {now}): to change "
                                         f"it, send base_version \"{now}\" (GET "
                                         f"/api/team/files/{name} gives the version)")
            raise TeamFileError(409, f"{name} changed on disk since version {base_version} "
                                     f"(now {now}): reload it, then edit")
        if name.startswith(LIB + "/"):
            (team_dir / LIB).mkdir(exist_ok=True)
        mode = 0o644
        if current is not None:
            mode = path.stat().st_mode & 0o777
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
            os.chmod(tmp, mode)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
    return version_of(data), time.time()
