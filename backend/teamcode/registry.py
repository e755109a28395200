"""The team folder as the station knows it: the files found (``discovery``), how each runs
(``state.FileRun``), and who wants to hear of a change (the hosts that reload). Lives on the
station thread; the watcher's thread hands it new listings through the station loop."""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from pathlib import Path

from .. import contract
from .discovery import Found, Stat, scan
from .state import ErrorInfo, FileRun

log = logging.getLogger("touchline.team")

#: ``(changed names, all found)``: called after a scan that changed something
ChangeListener = Callable[[set[str], dict[str, Found]], None]


class TeamRegistry:
    def __init__(self, team_dir: Path, builtin_plays: Iterable[str]) -> None:
        self.dir = team_dir
        self.builtin = tuple(builtin_plays)
        self.found: dict[str, Found] = {}
        self.runs: dict[str, FileRun] = {}
        self.generation = 0  # +1 on every change of the folder
        self.listeners: list[ChangeListener] = []
        if not team_dir.is_dir():
            log.warning("the team folder %s does not exist: no team code", team_dir)

    def rescan(self, stats: dict[str, Stat] | None = None) -> set[str]:
        """Looks at the folder again (``stats``: the watcher's listing); returns the names
        added, removed or changed (content, or a play name's clash), and tells the
        listeners."""
        old = self.found
        new = scan(self.dir, self.builtin, old, stats)
        changed = {n for n in set(old) | set(new)
                   if n not in old or n not in new or old[n].version != new[n].version
                   or old[n].clash != new[n].clash}
        if not changed:
            return changed
        self.found = new
        self.generation += 1
        for name in changed:
            if name not in new:
                self.runs.pop(name, None)
            else:
                self.runs.setdefault(name, FileRun())
        log.info("team folder: %s changed", ", ".join(sorted(changed)))
        for fn in self.listeners:
            fn(changed, new)
        return changed

    def plays(self) -> dict[str, Found]:
        """The team's plays by name (those that cannot load too: they fail when chosen)."""
        return {f.play: f for f in self.found.values() if f.play is not None and not f.clash}

    def processors(self) -> dict[str, Found]:
        """The team's processors by name (file stem)."""
        return {f.stem: f for f in self.found.values() if f.kind == "processor"}

    def run(self, name: str) -> FileRun:
        return self.runs.setdefault(name, FileRun())

    def file_view(self, f: Found) -> contract.TeamFile:
        r = self.runs.get(f.name) or FileRun()
        p50, p99 = r.tick_percentiles()
        err = r.error
        state: contract.TeamFileState
        if err is None and f.error is not None:  # found without running it
            state = "error"
            err = ErrorInfo(f.error.kind, f.error.message, f.name, f.error.line,
                            at_unix=f.mtime_unix)
        else:
            state = r.state
        return {
            "name": f.name, "kind": f.kind, "language": f.language, "play": f.play,
            "title": f.title or (f.play or f.stem), "description": f.description,
            "state": state, "error": None if err is None else err.view(),
            "version": f.version, "mtime_unix": f.mtime_unix, "size_bytes": f.stat.size,
            "reloaded_at_unix": r.reloaded_at_unix, "reloads": r.reloads, "ticks": r.ticks,
            "errors": r.errors, "overruns": r.overruns, "late": r.late, "moved_out": r.moved_out,
            "tick_ms_p50": p50, "tick_ms_p99": p99, "robots": list(r.robots),
            "outputs": dict(r.outputs),
        }

    def files_view(self) -> list[contract.TeamFile]:
        return [self.file_view(f) for f in self.found.values()]
