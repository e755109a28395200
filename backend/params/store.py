"""The parameter store: one current value, validated as a whole, versioned, persisted with
atomic writes, and named presets. The API is its only writer."""

from __future__ import annotations

import json
import logging
import os
import re
import tempfile
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, Future
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from domain.wallclock import file_stamp

from ..config import Settings
from ..contract import ParamChange
from .model import StationParams

log = logging.getLogger("touchline.params")
PRESET_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9 _.-]{0,63}$")


class PresetNotFound(KeyError):
    """No preset of that name."""


class ParamError(ValueError):
    """A change that was refused; ``errors`` has one ``{"loc", "msg", "type"}`` per field."""

    def __init__(self, errors: list[dict[str, Any]]) -> None:
        super().__init__("; ".join(f"{'.'.join(e['loc'])}: {e['msg']}" for e in errors))
        self.errors = errors


def format_errors(errors: Sequence[Any], prefix: tuple[str, ...] = ()) -> list[dict[str, Any]]:
    """Pydantic errors as ``{"loc", "msg", "type"}`` that JSON can carry: the input (which may
    be NaN) is left out, and a non-finite number gets a clear reason."""
    out = []
    for e in errors:
        msg = str(e.get("msg", "invalid"))
        if e.get("type") == "finite_number":
            msg = "must be a finite number (NaN and Infinity are not allowed)"
        out.append({"loc": [*prefix, *(str(p) for p in e.get("loc", ()))], "msg": msg,
                    "type": str(e.get("type", ""))})
    return out


def _errors(exc: ValidationError) -> list[dict[str, Any]]:
    return format_errors(exc.errors(), ("body",))


# Maps keyed by robot ("blue/3"): in a patch, ``null`` for a key removes that override.
OVERRIDE_MAPS = frozenset({"robots", "robot_overrides", "robot_plays"})

#: parameters that named a folder until issue 30, and the start-up setting (backend/config.py)
#: that sets it now. Files the station wrote before (params.json, presets) still load: these
#: are dropped from them with a log line; a request that carries one is refused.
MOVED_TO_START: dict[str, str] = {
    "strategy.scripts_dir": "scripts_dir",
    "recording.folder": "record_dir",
}
#: words that make an unknown key a path (refused with where folders are set instead)
_PATH_WORDS = frozenset({"dir", "dirs", "directory", "folder", "folders", "path", "paths",
                         "file", "files", "filename"})


def _moved_msg(dotted: str) -> str:
    field = MOVED_TO_START.get(dotted)
    if field is not None:
        meta = Settings.folder_fields()[field]
        return (f"folders are set when the station starts ({meta['flag']} or "
                f"{Settings.env_name(field)}), not as a parameter")
    return ("folders and files are set when the station starts (its command line or a "
            "TOUCHLINE_* environment variable; docs/security.md), not as parameters")


def path_errors(changes: Any, known: Any, path: tuple[str, ...] = ()) -> list[dict[str, Any]]:
    """The keys of a patch that are not parameters but name a folder or a file (a moved one,
    or any unknown key whose name says dir, folder, path, file): one error each, saying
    where it is set instead. Other unknown keys are left to the model's own refusal."""
    if not isinstance(changes, dict) or not isinstance(known, dict) \
            or (path and path[-1] in OVERRIDE_MAPS):  # keyed by robot: checked by its model
        return []
    out: list[dict[str, Any]] = []
    for k, v in changes.items():
        here = (*path, str(k))
        dotted = ".".join(here)
        if k in known:
            out += path_errors(v, known[k], here)
        elif dotted in MOVED_TO_START or _PATH_WORDS & set(str(k).lower().split("_")):
            out.append({"loc": ["body", *here], "msg": _moved_msg(dotted),
                        "type": "path_not_a_parameter"})
    return out


def drop_moved(values: dict[str, Any], where: str) -> dict[str, Any]:
    """``values`` (a file written before issue 30) without the parameters that became
    start-up settings; one log line names what was dropped."""
    dropped: list[str] = []
    out = dict(values)
    for dotted, field in MOVED_TO_START.items():
        group, key = dotted.split(".")
        g = out.get(group)
        if isinstance(g, dict) and key in g:
            out[group] = {k: v for k, v in g.items() if k != key}
            dropped.append(f"{dotted}={g[key]!r} (now {Settings.folder_fields()[field]['flag']})")
    if dropped:
        log.warning("%s: dropped %s: folders are set when the station starts", where,
                    ", ".join(dropped))
    return out


def deep_merge(base: dict[str, Any], patch: dict[str, Any],
               deletable: bool = False) -> dict[str, Any]:
    out = dict(base)
    for k, v in patch.items():
        if deletable and v is None:
            out.pop(k, None)
        elif isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = deep_merge(out[k], v, deletable=k in OVERRIDE_MAPS)
        else:
            out[k] = v
    return out


def diff(a: dict[str, Any], b: dict[str, Any],
         path: tuple[str, ...] = ()) -> list[ParamChange]:
    """Leaves that differ between two parameter trees: ``{"path", "from", "to"}``."""
    out: list[ParamChange] = []
    for k in sorted(set(a) | set(b)):
        va, vb = a.get(k), b.get(k)
        if isinstance(va, dict) and isinstance(vb, dict):
            out += diff(va, vb, (*path, k))
        elif va != vb:
            out.append({"path": ".".join((*path, k)), "from": va, "to": vb})
    return out


def _leaves(tree: dict[str, Any], path: tuple[str, ...] = ()
            ) -> list[tuple[tuple[str, ...], Any]]:
    out: list[tuple[tuple[str, ...], Any]] = []
    for k, v in tree.items():
        if isinstance(v, dict) and v:
            out += _leaves(v, (*path, str(k)))
        else:
            out.append(((*path, str(k)), v))
    return out


def parse_setting(item: str) -> dict[str, Any]:
    """``"group.key=value"`` (a command-line override) as a patch ``{"group": {"key": value}}``.
    The value is JSON when it parses (numbers, true, null, objects), else the text itself."""
    key, sep, raw = item.partition("=")
    parts = [p for p in key.strip().split(".") if p]
    if not sep or not parts:
        raise ValueError(f"expected group.key=value, got {item!r}")
    try:
        value: Any = json.loads(raw)
    except ValueError:
        value = raw
    out: dict[str, Any] = {parts[-1]: value}
    for p in reversed(parts[:-1]):
        out = {p: out}
    return out


def run_now(write: Callable[[], None]) -> None:
    """A file write run where it is asked for (no writer thread)."""
    write()


def atomic_write_json(path: Path, data: Any) -> None:
    """Write-then-rename: a crash leaves either the old file or the new one, never half."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(data, f, indent=2, sort_keys=True)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        dfd = os.open(path.parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


#: the layout of params.json; a file with a newer schema is set aside, not misread
FILE_SCHEMA = 1


class ParamStore:
    def __init__(self, state_dir: Path | None) -> None:
        self.state_dir = state_dir
        self.defaults = StationParams()
        self.current = StationParams()
        self.version = 0
        #: dotted leaf path -> the version that last changed it (since the start): a change
        #: made on an older version of the page is refused for the leaves changed since
        self.changed_in: dict[str, int] = {}
        self._listeners: list[Callable[[StationParams, int], None]] = []
        #: the plays that may be chosen now (built-in and the team folder's); None: any name
        #: the schema's pattern takes (a store without a station)
        self.play_names: Callable[[], Sequence[str]] | None = None
        #: problems with the state folder found at start-up (health shows them)
        self.warnings: list[str] = []
        #: where params.json is written: None writes it at once (a store without a station);
        #: the station gives one thread of its own, so a change is applied on the station
        #: thread without its fsync holding that thread (writes stay in order)
        self.writer: Executor | None = None
        #: the write of the last change (None: written at once, or nothing to write): a
        #: route answers once the change it made is on disk
        self.saved: Future[None] | None = None
        if state_dir is not None:
            self._load()

    @property
    def file(self) -> Path | None:
        return None if self.state_dir is None else self.state_dir / "params.json"

    @property
    def presets_dir(self) -> Path | None:
        return None if self.state_dir is None else self.state_dir / "presets"

    def _load(self) -> None:
        """The stored parameters, or the defaults. Whatever the state folder holds (another
        JSON type, wrong field types, a newer file schema, invalid UTF-8, a folder in place of
        the file, an unreadable file), the station starts: a file that cannot be used is set
        aside under a new name (never deleted), the defaults are used, the log and
        ``warnings`` (health, the page) say so, and nothing of the bad file stays in use."""
        f = self.file
        if f is None or not f.exists():
            return
        try:
            data = json.loads(f.read_bytes().decode("utf-8"))
            if not isinstance(data, dict):
                raise ValueError(f"expected a JSON object, found {type(data).__name__}")
            schema = data.get("schema", 1)
            if not isinstance(schema, int) or isinstance(schema, bool) or schema > FILE_SCHEMA:
                raise ValueError(f"file schema {schema!r} is newer than this station's "
                                 f"({FILE_SCHEMA})")
            values = data.get("values", {})
            if not isinstance(values, dict):
                raise ValueError(f"'values' is a {type(values).__name__}, not an object")
            version = data.get("version", 0)
            if not isinstance(version, int) or isinstance(version, bool) or version < 0:
                raise ValueError(f"'version' is {version!r}, not a whole number >= 0")
            # unknown or removed keys from an older version are dropped, not fatal
            current = StationParams.model_validate(
                _known_only(self.defaults.model_dump(), drop_moved(values, str(f))))
        except (ValueError, ValidationError, OSError, RecursionError) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            self._set_aside(f, reason)
            return
        self.current, self.version = current, version  # all of it, or nothing
        log.info("parameters loaded from %s (version %d)", f, self.version)

    def _set_aside(self, f: Path, reason: str) -> None:
        bad = f.with_name(f"{f.stem}.invalid-{file_stamp()}{f.suffix}")
        try:
            os.replace(f, bad)
            where = f"set aside as {bad.name}"
        except OSError as exc:
            where = f"could not be set aside ({exc}): fix or remove it"
        msg = f"{f.name} was not usable ({reason}); {where}; default parameters in use"
        log.error("parameters: %s", msg)
        self.warnings.append(msg)

    def subscribe(self, fn: Callable[[StationParams, int], None]) -> None:
        self._listeners.append(fn)

    def values(self) -> dict[str, Any]:
        return self.current.model_dump(mode="json")

    def schema(self) -> dict[str, Any]:
        """The JSON schema, with the plays known now as ``strategy.play``'s choices (the
        team folder's plays come and go with its files)."""
        schema = StationParams.model_json_schema()
        if self.play_names is not None:
            strategy = schema.get("$defs", {}).get("StrategyParams", {})
            play = strategy.get("properties", {}).get("play")
            if isinstance(play, dict):
                play["enum"] = list(self.play_names())
        return schema

    def _check_plays(self, new: StationParams) -> None:
        """A play chosen (for the team or a robot) must be known now; one already in force
        may stay (its file may be gone for a moment: its robots stop meanwhile)."""
        if self.play_names is None:
            return
        known = set(self.play_names())
        old, sp = self.current.strategy, new.strategy
        errors: list[dict[str, Any]] = []
        if sp.play != old.play and sp.play not in known:
            errors.append({"loc": ["body", "strategy", "play"], "type": "enum",
                           "msg": f"no play named {sp.play!r}; plays: "
                                  f"{', '.join(sorted(known))}"})
        for rid, play in sp.robot_plays.items():
            if play != old.robot_plays.get(rid) and play not in known:
                errors.append({"loc": ["body", "strategy", "robot_plays", rid], "type": "enum",
                               "msg": f"no play named {play!r}; plays: "
                                      f"{', '.join(sorted(known))}"})
        if errors:
            raise ParamError(errors)

    def patch(self, changes: dict[str, Any]) -> StationParams:
        """Validates the whole result, then applies it at once; nothing applied on error."""
        if not isinstance(changes, dict):
            raise ParamError([{"loc": ["body"], "msg": "expected an object of changes",
                               "type": "type_error"}])
        self._refuse_paths(changes)
        merged = deep_merge(self.values(), changes)
        try:
            new = StationParams.model_validate(merged)
        except ValidationError as exc:
            raise ParamError(_errors(exc)) from None
        self._check_plays(new)
        return self._set(new)

    def replace(self, values: dict[str, Any]) -> StationParams:
        """Whole-tree import: missing keys take their defaults."""
        return self.patch_from(self.defaults.model_dump(mode="json"), values)

    def patch_from(self, base: dict[str, Any], values: dict[str, Any]) -> StationParams:
        if not isinstance(values, dict):
            raise ParamError([{"loc": ["body"], "msg": "expected an object of parameter "
                               "groups", "type": "type_error"}])
        self._refuse_paths(values)
        try:
            new = StationParams.model_validate(deep_merge(base, values))
        except ValidationError as exc:
            raise ParamError(_errors(exc)) from None
        self._check_plays(new)
        return self._set(new)

    def _refuse_paths(self, changes: dict[str, Any]) -> None:
        errors = path_errors(changes, self.defaults.model_dump())
        if errors:
            raise ParamError(errors)

    def _set(self, new: StationParams) -> StationParams:
        self.saved = None
        if new == self.current:
            return new
        changed = diff(self.values(), new.model_dump(mode="json"))
        self.current = new
        self.version += 1
        for c in changed:
            self.changed_in[c["path"]] = self.version
        if self.file is not None:
            data = {"schema": FILE_SCHEMA, "version": self.version, "values": self.values()}
            if self.writer is None:
                atomic_write_json(self.file, data)
            else:
                self.saved = self.writer.submit(atomic_write_json, self.file, data)
        for fn in self._listeners:
            fn(new, self.version)
        return new

    def changed_since(self, changes: Any, version: int) -> list[ParamChange]:
        """The leaves ``changes`` (a patch) would set that changed after ``version`` (the one
        the caller saw): ``{"path", "from": what the caller wants, "to": the value now}``."""
        if not isinstance(changes, dict):
            return []
        values = self.values()
        out: list[ParamChange] = []
        for path, wanted in _leaves(changes):
            dotted = ".".join(path)
            if any(v > version and (k == dotted or k.startswith(dotted + "."))
                   for k, v in self.changed_in.items()):
                now: Any = values
                for part in path:
                    now = now.get(part) if isinstance(now, dict) else None
                out.append({"path": dotted, "from": wanted, "to": now})
        return out

    def diff_from_defaults(self) -> list[ParamChange]:
        return diff(self.defaults.model_dump(mode="json"), self.values())

    # ---- presets ----

    def _preset_path(self, name: str) -> Path:
        if not PRESET_NAME.match(name):
            raise ParamError([{"loc": ["path", "name"], "type": "value_error",
                               "msg": "preset names are 1-64 letters, digits, space, _ . -"}])
        d = self.presets_dir
        if d is None:
            raise ParamError([{"loc": ["path", "name"], "type": "value_error",
                               "msg": "presets need a state directory"}])
        return d / f"{name}.json"

    def list_presets(self) -> list[str]:
        d = self.presets_dir
        if d is None or not d.exists():
            return []
        return sorted(p.stem for p in d.glob("*.json"))

    def save_preset(self, name: str) -> None:
        atomic_write_json(self._preset_path(name), {"values": self.values()})

    def read_preset(self, name: str) -> dict[str, Any]:
        p = self._preset_path(name)
        if not p.exists():
            raise PresetNotFound(name)
        try:
            data = json.loads(p.read_bytes().decode("utf-8"))
            values = data["values"]
            if not isinstance(values, dict):
                raise ValueError("'values' is not an object")
        except (ValueError, KeyError, TypeError, OSError, RecursionError) as exc:
            raise ParamError([{"loc": ["path", "name"], "type": "value_error",
                               "msg": f"preset {name!r} is not a valid preset file: {exc}"}]) \
                from None
        return drop_moved(values, f"preset {name!r}")

    def load_preset(self, name: str) -> StationParams:
        return self.replace(self.read_preset(name))

    def delete_preset(self, name: str) -> None:
        p = self._preset_path(name)
        if not p.exists():
            raise PresetNotFound(name)
        p.unlink()


def _known_only(template: dict[str, Any], values: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in template.items():
        if k not in values:
            out[k] = v
        elif isinstance(v, dict) and isinstance(values[k], dict) and v:
            out[k] = _known_only(v, values[k])
        else:
            out[k] = values[k]
    return out
