"""Random access to one log for a replay player: a sparse time index built in one pass
(cached under ``cache_dir``), seeking by time, streaming from an offset, stepping back.

A gzip log is decompressed once into a plain copy under ``cache_dir`` so it can be seeked."""

from __future__ import annotations

import bisect
import hashlib
import json
import os
import zlib
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

from ssllog.format import (
    FILE_HEADER,
    HEADER_MAGIC,
    HEADER_SIZE,
    KNOWN_TYPES,
    MAX_PAYLOAD,
    RECORD_HEADER,
    RECORD_HEADER_SIZE,
    TYPE_INDEX_2021,
    TYPE_REFEREE_2013,
    TYPE_TL_ACTION,
    TYPE_VISION_2010,
    TYPE_VISION_2014,
)
from ssllog.reader import LogFormatError, Record
from sslpb import ssl_gc_referee_message_pb2

Progress = Callable[[float], None]

INDEX_EVERY = 64  # records between two entries of the sparse index
GAP_NS = 1_000_000_000  # no vision for longer than this is a gap
BLOCK = 8 * 1024 * 1024  # bytes read at once by the index pass
CACHE_VERSION = 3  # bumped when the pass learns something new: older caches are redone
GUNZIP_SHARE = 0.7  # of the progress bar, when a gzip file is first copied then indexed
VISION_TYPES = (TYPE_VISION_2010, TYPE_VISION_2014)
TYPE_NAMES = {
    0: "blank",
    1: "unknown",
    2: "vision 2010",
    3: "referee 2013",
    4: "vision 2014",
    5: "tracker 2020",
    6: "index 2021",
    1001: "touchline commands",
    1002: "touchline params",
    1003: "touchline action",
    1004: "touchline health",
    1005: "touchline session",
    1006: "touchline team",
}

_Referee = ssl_gc_referee_message_pb2.Referee


class NotCached(LookupError):
    """``LogFile.open(..., build=False)`` found no index (or gzip copy) of the file as it is now
    in the cache."""


@dataclass(frozen=True, slots=True)
class LogEvent:
    """A point on the timeline: kind is command, stage, goal or card; team is blue/yellow/''."""

    time_ns: int
    kind: str
    label: str
    team: str = ""


@dataclass(slots=True)
class _Index:
    """Everything the one pass learns; saved as JSON in the cache."""

    data_size: int = 0
    data_end: int = HEADER_SIZE  # end of the last complete record
    offsets: list[int] = field(default_factory=list)
    times: list[int] = field(default_factory=list)
    counts: dict[int, int] = field(default_factory=dict)
    t_first_ns: int = 0
    t_last_ns: int = 0
    events: list[LogEvent] = field(default_factory=list)
    cameras: dict[int, int] = field(default_factory=dict)
    gaps: list[tuple[int, int]] = field(default_factory=list)
    teams: dict[str, str] = field(default_factory=dict)
    warning: str | None = None
    has_index_record: bool = False

    def to_json(self) -> dict[str, Any]:
        d = asdict(self)
        d["events"] = [asdict(e) for e in self.events]
        d["version"] = CACHE_VERSION
        return d

    @staticmethod
    def from_json(d: dict[str, Any]) -> _Index:
        return _Index(
            data_size=int(d["data_size"]),
            data_end=int(d["data_end"]),
            offsets=[int(x) for x in d["offsets"]],
            times=[int(x) for x in d["times"]],
            counts={int(k): int(v) for k, v in d["counts"].items()},
            t_first_ns=int(d["t_first_ns"]),
            t_last_ns=int(d["t_last_ns"]),
            events=[LogEvent(**e) for e in d["events"]],
            cameras={int(k): int(v) for k, v in d["cameras"].items()},
            gaps=[(int(a), int(b)) for a, b in d["gaps"]],
            teams={str(k): str(v) for k, v in d["teams"].items()},
            warning=d["warning"],
            has_index_record=bool(d["has_index_record"]),
        )


def _read_json(path: Path) -> dict[str, Any] | None:
    """A cache file, or None if it is missing or unreadable (then the work is done again)."""
    try:
        d = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return d if isinstance(d, dict) else None


def _write_json(path: Path, data: dict[str, Any]) -> None:
    """Temp name, then rename: a reader never sees half a cache file."""
    tmp = path.with_name(path.name + f".tmp{os.getpid()}")
    tmp.write_text(json.dumps(data))
    os.replace(tmp, path)


def _scaled(progress: Progress | None, lo: float, hi: float) -> Progress | None:
    """One bar for two passes (gunzip, then index): maps 0..1 onto lo..hi."""
    if progress is None:
        return None
    cb = progress
    return lambda f: cb(lo + (hi - lo) * f)


def cache_key(path: str) -> str:
    """Absolute path + size + mtime: a changed or replaced file gets a new key."""
    st = os.stat(path)
    raw = f"{os.path.abspath(path)}\0{st.st_size}\0{st.st_mtime_ns}"
    return hashlib.sha256(raw.encode()).hexdigest()[:24]


def _gunzip_copy(path: str, dest: Path, progress: Progress | None) -> str | None:
    """Decompresses ``path`` into ``dest`` (temp name, then rename). zlib directly rather
    than GzipFile: a stream cut short (recorder killed) keeps every byte decoded before the
    cut, and a warning is returned."""
    tmp = dest.with_name(dest.name + f".tmp{os.getpid()}")
    total = max(1, os.path.getsize(path))
    d = zlib.decompressobj(wbits=31)
    done = 0
    try:
        with open(path, "rb") as raw, open(tmp, "wb") as out:
            while chunk := raw.read(1024 * 1024):
                done += len(chunk)
                while chunk:
                    if d.eof:  # a concatenated gzip member follows
                        d = zlib.decompressobj(wbits=31)
                    out.write(d.decompress(chunk))
                    chunk = d.unused_data if d.eof else b""
                if progress is not None:
                    progress(min(1.0, done / total))
            out.write(d.flush())
        os.replace(tmp, dest)
    except zlib.error as e:
        raise LogFormatError(0, f"bad gzip data ({e})") from e
    finally:
        if tmp.exists():
            tmp.unlink()
    if progress is not None:
        progress(1.0)
    if not d.eof:
        return "the compressed stream ends early (a recording that was killed?)"
    return None


def _camera_id(buf: bytes | memoryview, pos: int, end: int) -> int | None:
    """camera_id of an SSL_WrapperPacket at buf[pos:end] without protobuf: wrapper field 1
    (detection, length-delimited) -> detection field 4 (varint). None if absent or garbled."""
    while pos < end:
        tag = buf[pos]
        pos += 1
        if tag & 0x80:  # a multi-byte tag: not one we look for, decode generically
            shift, tag = 7, tag & 0x7F
            while True:
                if pos >= end:
                    return None
                b = buf[pos]
                pos += 1
                tag |= (b & 0x7F) << shift
                shift += 7
                if not b & 0x80:
                    break
        wt = tag & 7
        if wt == 0:
            v, shift = 0, 0
            while True:
                if pos >= end:
                    return None
                b = buf[pos]
                pos += 1
                v |= (b & 0x7F) << shift
                shift += 7
                if not b & 0x80:
                    break
            if tag == 0x20:  # detection.camera_id
                return v
        elif wt == 1:
            pos += 8
        elif wt == 5:
            pos += 4
        elif wt == 2:
            n, shift = 0, 0
            while True:
                if pos >= end:
                    return None
                b = buf[pos]
                pos += 1
                n |= (b & 0x7F) << shift
                shift += 7
                if not b & 0x80:
                    break
            if tag == 0x0A:  # wrapper.detection: descend into it
                end = min(end, pos + n)
                continue
            pos += n
        else:
            return None
    return None


def _action_label(payload: bytes) -> str:
    """A Touchline operator action (type 1003, JSON) as a timeline label; "" if unreadable."""
    try:
        a = json.loads(payload)
    except ValueError:
        return ""
    if not isinstance(a, dict) or not isinstance(a.get("action"), str):
        return ""
    what = [str(a["action"])]
    for key in ("command", "card", "team", "id"):
        if key in a and a[key] is not None:
            what.append(str(a[key]))
    by = a.get("by")
    return " ".join(what) + (f" ({by})" if isinstance(by, str) and by else "")


class _RefereeTracker:
    """Turns the referee stream into timeline events by comparing with the previous message."""

    def __init__(self, events: list[LogEvent], teams: dict[str, str]) -> None:
        self.events = events
        self.teams = teams
        self.counter: int | None = None
        self.stage: int | None = None
        self.prev: dict[str, tuple[int, int, int]] = {}

    def feed(self, time_ns: int, payload: bytes) -> None:
        ref = _Referee()
        try:
            ref.ParseFromString(payload)
        except Exception:  # a garbled referee message is skipped, not fatal
            return
        if ref.HasField("stage") and ref.stage != self.stage:
            self.stage = ref.stage
            self.events.append(LogEvent(time_ns, "stage", _enum_name(_Referee.Stage, ref.stage)))
        if ref.HasField("command_counter") and ref.command_counter != self.counter:
            self.counter = ref.command_counter
            name = _enum_name(_Referee.Command, ref.command)
            team = next((c for c in ("yellow", "blue") if name.endswith("_" + c.upper())), "")
            self.events.append(LogEvent(time_ns, "command", name, team))
        for color in ("yellow", "blue"):
            if not ref.HasField(color):
                continue
            info = getattr(ref, color)
            if info.name:
                self.teams[color] = info.name
            now = (info.score, info.yellow_cards, info.red_cards)
            before = self.prev.get(color)
            self.prev[color] = now
            if before is None:
                continue
            who = info.name or color
            if now[0] > before[0]:
                score = f"{ref.yellow.score}:{ref.blue.score}"
                self.events.append(LogEvent(time_ns, "goal", f"{who} ({score})", color))
            if now[1] > before[1]:
                self.events.append(LogEvent(time_ns, "card", f"yellow card {who}", color))
            if now[2] > before[2]:
                self.events.append(LogEvent(time_ns, "card", f"red card {who}", color))


def _enum_name(enum: Any, value: int) -> str:
    try:
        return str(enum.Name(value))
    except ValueError:
        return str(value)


def _check_header(head: bytes) -> None:
    if len(head) < HEADER_SIZE:
        raise LogFormatError(0, "file shorter than the 16-byte header")
    magic, version = FILE_HEADER.unpack_from(head)
    if magic != HEADER_MAGIC:
        raise LogFormatError(0, f"bad magic {magic!r}")
    if version != 1:
        raise LogFormatError(12, f"unsupported version {version}")


def build_index(data_path: str, progress: Progress | None = None) -> _Index:
    """The one pass over the plain file: reads big blocks and unpacks record headers from
    them; only referee records are decoded with protobuf (vision is scanned for camera_id)."""
    idx = _Index()
    size = os.path.getsize(data_path)
    idx.data_size = size
    counts: dict[int, int] = {}
    cameras: dict[int, int] = {}
    gaps: list[tuple[int, int]] = []
    offsets: list[int] = []
    times: list[int] = []
    referee = _RefereeTracker(idx.events, idx.teams)
    unpack = RECORD_HEADER.unpack_from
    n_records = 0
    last_off = last_t = -1
    first_t: int | None = None
    last_vision: int | None = None
    next_progress = 0.0
    with open(data_path, "rb", buffering=0) as f:
        _check_header(f.read(HEADER_SIZE))
        buf = b""
        base = HEADER_SIZE  # file offset of buf[0]
        pos = 0
        eof = False
        while True:
            avail = len(buf) - pos
            if not eof:
                # refill when what is left does not hold the whole next record
                need = RECORD_HEADER_SIZE
                if avail >= RECORD_HEADER_SIZE:
                    need += min(MAX_PAYLOAD, max(0, unpack(buf, pos)[2]))
                if avail < need:
                    chunk = f.read(max(BLOCK, need))
                    if not chunk:
                        eof = True
                    base += pos
                    buf = buf[pos:] + chunk
                    pos = 0
                    if progress is not None and base / max(1, size) >= next_progress:
                        progress(min(1.0, base / max(1, size)))
                        next_progress += 0.01
                    continue
            avail = len(buf) - pos
            if avail == 0:
                break
            offset = base + pos
            if avail < RECORD_HEADER_SIZE:
                idx.warning = f"truncated record header at byte {offset}"
                break
            t, rtype, n = unpack(buf, pos)
            if n < 0 or n > MAX_PAYLOAD:
                raise LogFormatError(offset, f"payload size {n}")
            if avail < RECORD_HEADER_SIZE + n:
                if eof:
                    idx.warning = (
                        f"truncated record at byte {offset}: "
                        f"{avail - RECORD_HEADER_SIZE} of {n} bytes"
                    )
                    break
                continue  # the refill above reads enough
            start = pos + RECORD_HEADER_SIZE
            pos = start + n
            counts[rtype] = counts.get(rtype, 0) + 1
            if rtype == TYPE_INDEX_2021:
                idx.has_index_record = True
                continue
            if n_records % INDEX_EVERY == 0:
                offsets.append(offset)
                times.append(t)
            n_records += 1
            last_off, last_t = offset, t
            if first_t is None:
                first_t = t
            if rtype in VISION_TYPES:
                cam = _camera_id(buf, start, pos)
                if cam is not None:
                    cameras[cam] = cameras.get(cam, 0) + 1
                # a silence before the first frame counts too (from the log's first record)
                prev = last_vision if last_vision is not None else first_t
                if prev is not None and t - prev > GAP_NS:
                    gaps.append((prev, t))
                last_vision = t
            elif rtype == TYPE_REFEREE_2013:
                referee.feed(t, buf[start:pos])
            elif rtype == TYPE_TL_ACTION:
                label = _action_label(bytes(buf[start:pos]))
                if label:
                    referee.events.append(LogEvent(t, "operator", label))
    if last_off >= 0 and (not offsets or offsets[-1] != last_off):
        offsets.append(last_off)
        times.append(last_t)
    idx.data_end = base + pos
    idx.offsets, idx.times = offsets, times
    idx.counts, idx.cameras = counts, cameras
    idx.t_first_ns = first_t if first_t is not None else 0
    idx.t_last_ns = last_t if last_off >= 0 else idx.t_first_ns
    if last_vision is None and first_t is not None and idx.t_last_ns - first_t > GAP_NS:
        gaps.append((first_t, idx.t_last_ns))
    elif last_vision is not None and idx.t_last_ns - last_vision > GAP_NS:
        gaps.append((last_vision, idx.t_last_ns))
    idx.gaps = gaps
    if progress is not None:
        progress(1.0)
    return idx


class LogFile:
    """One log opened for replay. Use `LogFile.open`; call `close()` when done."""

    def __init__(self, path: str, data_path: str, index: _Index) -> None:
        self.path = path
        self.data_path = data_path
        self._ix = index
        self._f: BinaryIO = open(data_path, "rb")  # noqa: SIM115 - closed by close()
        # running maximum of the sampled times: bisect stays correct if receive times jitter
        self._tmax: list[int] = []
        m = -(1 << 63)
        for t in index.times:
            m = max(m, t)
            self._tmax.append(m)

    @classmethod
    def open(
        cls, path: str, cache_dir: str | Path, progress: Progress | None = None,
        *, build: bool = True,
    ) -> LogFile:
        """Opens ``path``; the gzip copy and the index are taken from ``cache_dir`` when a
        previous open of the same (unchanged) file left them there. ``build=False``: only
        from the cache (``NotCached`` if it has not got them: the slow pass is not done)."""
        cache = Path(cache_dir)
        cache.mkdir(parents=True, exist_ok=True)
        key = cache_key(path)
        gz_warning: str | None = None
        if path.endswith("gz"):
            copy = cache / f"{key}.log"
            done = cache / f"{key}.gunzip.json"
            marker = _read_json(done) if copy.exists() else None
            if marker is None or "warning" not in marker:
                if not build:
                    raise NotCached(f"{path} has no decompressed copy in {cache}")
                gz_warning = _gunzip_copy(path, copy, _scaled(progress, 0.0, GUNZIP_SHARE))
                _write_json(done, {"warning": gz_warning})
            else:
                gz_warning = marker["warning"]
            data_path = str(copy)
        else:
            data_path = path
        index_file = cache / f"{key}.index.json"
        index: _Index | None = None
        d = _read_json(index_file)
        if d is not None and d.get("version") == CACHE_VERSION:
            try:
                index = _Index.from_json(d)
            except (ValueError, KeyError, TypeError):
                index = None
            if index is not None and index.data_size != os.path.getsize(data_path):
                index = None
        if index is None:
            if not build:
                raise NotCached(f"{path} has no index in {cache}")
            share = GUNZIP_SHARE if data_path != path else 0.0
            index = build_index(data_path, _scaled(progress, share, 1.0))
            if gz_warning and not index.warning:
                index.warning = gz_warning
            _write_json(index_file, index.to_json())
        return cls(path, data_path, index)

    # --- summary -------------------------------------------------------------------------

    @property
    def t_first_ns(self) -> int:
        return self._ix.t_first_ns

    @property
    def t_last_ns(self) -> int:
        return self._ix.t_last_ns

    @property
    def duration_s(self) -> float:
        return (self._ix.t_last_ns - self._ix.t_first_ns) / 1e9

    @property
    def counts(self) -> dict[int, int]:
        return dict(self._ix.counts)

    @property
    def events(self) -> list[LogEvent]:
        return list(self._ix.events)

    @property
    def cameras(self) -> dict[int, int]:
        return dict(self._ix.cameras)

    @property
    def gaps(self) -> list[tuple[int, int]]:
        """(last vision time, next vision time) of every silence longer than 1 s, in ns."""
        return list(self._ix.gaps)

    @property
    def teams(self) -> dict[str, str]:
        return dict(self._ix.teams)

    @property
    def warning(self) -> str | None:
        return self._ix.warning

    @property
    def unknown_types(self) -> dict[int, int]:
        return {t: n for t, n in self._ix.counts.items() if t not in KNOWN_TYPES}

    @property
    def data_end(self) -> int:
        """End of the last complete record: records past it (a truncated tail) are ignored."""
        return self._ix.data_end

    @property
    def has_index_record(self) -> bool:
        return self._ix.has_index_record

    # --- random access -------------------------------------------------------------------

    def _header_at(self, offset: int) -> tuple[int, int, int]:
        self._f.seek(offset)
        h = self._f.read(RECORD_HEADER_SIZE)
        if len(h) < RECORD_HEADER_SIZE:
            raise LogFormatError(offset, "record header past the end")
        t, rtype, n = RECORD_HEADER.unpack(h)
        if n < 0 or n > MAX_PAYLOAD:
            raise LogFormatError(offset, f"payload size {n}")
        return t, rtype, n

    def offset_at(self, time_ns: int) -> int:
        """Offset of the first record received at or after ``time_ns`` (``data_end`` if none):
        bisect the sparse index, then scan at most INDEX_EVERY record headers."""
        i = bisect.bisect_left(self._tmax, time_ns)
        if i == 0:
            return self._ix.offsets[0] if self._ix.offsets else self.data_end
        off = self._ix.offsets[i - 1]
        end = self.data_end
        while off < end:
            t, rtype, n = self._header_at(off)
            if t >= time_ns and rtype != TYPE_INDEX_2021:
                return off
            off += RECORD_HEADER_SIZE + n
        return end

    def read_at(self, offset: int) -> Record:
        """The record starting at ``offset`` (which must be a record start)."""
        t, rtype, n = self._header_at(offset)
        payload = self._f.read(n)
        if len(payload) < n:
            raise LogFormatError(offset, "record past the end")
        return Record(offset, t, rtype, payload)

    def records(
        self, from_offset: int | None = None, include_unknown: bool = False
    ) -> Iterator[Record]:
        """Streams records from ``from_offset`` (a record start; default the first record),
        skipping index records and, unless asked, types this reader does not know."""
        off = HEADER_SIZE if from_offset is None else from_offset
        end = self.data_end
        with open(self.data_path, "rb", buffering=1024 * 1024) as f:
            f.seek(off)
            while off < end:
                h = f.read(RECORD_HEADER_SIZE)
                if len(h) < RECORD_HEADER_SIZE:
                    return
                t, rtype, n = RECORD_HEADER.unpack(h)
                if n < 0 or n > MAX_PAYLOAD:
                    raise LogFormatError(off, f"payload size {n}")
                payload = f.read(n)
                if len(payload) < n:
                    return
                if rtype != TYPE_INDEX_2021 and (include_unknown or rtype in KNOWN_TYPES):
                    yield Record(off, t, rtype, payload)
                off += RECORD_HEADER_SIZE + n

    def prev_record_offset(self, offset: int, rtype: int) -> int | None:
        """Offset of the last record of type ``rtype`` that starts before ``offset`` (to step
        one vision frame back): scan forward from the index entry before it, going further
        back an entry at a time when that stretch has none."""
        offs = self._ix.offsets
        i = bisect.bisect_left(offs, offset)
        hi = offset
        while i > 0:
            i -= 1
            off = offs[i]
            found: int | None = None
            while off < hi:
                _, t, n = self._header_at(off)
                if t == rtype:
                    found = off
                off += RECORD_HEADER_SIZE + n
            if found is not None:
                return found
            hi = offs[i]
        return None

    def close(self) -> None:
        self._f.close()

    def __enter__(self) -> LogFile:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
