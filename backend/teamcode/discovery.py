"""What the team folder holds, found WITHOUT running any of it in the station's process.

* ``*.py`` in the folder's top level, read with ``ast.parse``: a top-level ``def play(`` or
  ``class Play`` makes a **play**; a top-level class deriving from ``Processor`` a
  **processor**; anything else is a **library** (importable by the others). Module-level
  string constants ``TITLE`` and ``DESCRIPTION`` name it in the selector.
* ``*.m`` in the top level: a **play** when its first function is named after the file
  (``function orders = name(ours, theirs, ball, game)``, the paper's way); its help text (the
  comment lines right after that line) gives the title (first line) and the description.
  Other ``.m`` files are libraries on the Octave path.
* ``lib/`` (the only subfolder looked at): ``*.py`` and ``*.m`` libraries.

A play is named after its file's stem (``pass_drill.py`` -> ``pass_drill``). A stem that is a
built-in play's name, or another play file's, is an error of that file ("import" kind).
"""

from __future__ import annotations

import ast
import hashlib
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

Kind = Literal["play", "processor", "library"]
Language = Literal["python", "octave"]

#: the names a team file may have (the API's PUT refuses others): a top-level or lib/ file
#: whose stem is an identifier both Python and Octave accept
NAME_RE = re.compile(r"^(lib/)?[A-Za-z][A-Za-z0-9_]{0,62}\.(py|m)$")
LIB = "lib"

_M_FUNCTION = re.compile(
    r"^\s*function\s+(?:(?:\[[^\]]*\]|[A-Za-z]\w*)\s*=\s*)?([A-Za-z]\w*)\s*(?:\(|$|%|#)")
# guesses for a file that does not parse (its kind while it is broken)
_PY_PLAY_GUESS = re.compile(r"^(def\s+play\s*\(|class\s+Play\b)", re.M)
_PY_PROC_GUESS = re.compile(r"^class\s+\w+\s*\([^)]*\bProcessor\b", re.M)


@dataclass(frozen=True, slots=True)
class Stat:
    """What the watcher compares: a change of any of these is a save."""

    mtime_ns: int
    size: int
    inode: int


@dataclass(frozen=True, slots=True)
class Problem:
    """Why a file cannot load, found without running it."""

    kind: Literal["import"]
    message: str
    line: int | None = None


@dataclass(frozen=True, slots=True)
class Found:
    """One file of the team folder."""

    name: str  # "pass_drill.py", "lib/util.m"
    path: Path
    kind: Kind
    language: Language
    play: str | None  # the play's name (plays only)
    title: str
    description: str
    version: str  # 12 hex digits of the content's SHA-256
    stat: Stat
    #: how to run it: "function" (def play), "class" (class Play), the processor's class
    #: name, "octave" (a .m play); "" for libraries
    entry: str = ""
    problem: Problem | None = None  # found in the file itself
    #: the play's name is taken (a built-in play's, or another file's): set by the scan
    clash: str = ""

    @property
    def error(self) -> Problem | None:
        """Why it cannot load: its own problem, else a name clash."""
        if self.problem is not None:
            return self.problem
        return Problem("import", self.clash) if self.clash else None

    @property
    def stem(self) -> str:
        return self.name.rsplit("/", 1)[-1].rsplit(".", 1)[0]

    @property
    def mtime_unix(self) -> float:
        return self.stat.mtime_ns / 1e9


def version_of(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:12]


def list_files(team_dir: Path) -> dict[str, Stat]:
    """The team files (top level and ``lib/``) with their stats; names sorted. A folder that
    is missing or unreadable holds nothing."""
    out: dict[str, Stat] = {}
    for sub in ("", LIB):
        folder = team_dir / sub if sub else team_dir
        try:
            entries = list(os.scandir(folder))
        except OSError:
            continue
        for e in entries:
            name = f"{sub}/{e.name}" if sub else e.name
            if not NAME_RE.match(name):
                continue  # hidden files, editors' backups, temporary files of a save
            try:
                if not e.is_file():
                    continue
                st = e.stat()
            except OSError:
                continue
            out[name] = Stat(st.st_mtime_ns, st.st_size, st.st_ino)
    return dict(sorted(out.items()))


def _str_constant(node: ast.stmt, name: str) -> str | None:
    target: ast.expr | None = None
    value: ast.expr | None = None
    if isinstance(node, ast.Assign) and len(node.targets) == 1:
        target, value = node.targets[0], node.value
    elif isinstance(node, ast.AnnAssign):
        target, value = node.target, node.value
    if isinstance(target, ast.Name) and target.id == name and isinstance(value, ast.Constant) \
            and isinstance(value.value, str):
        return value.value
    return None


def _derives_from_processor(cls: ast.ClassDef) -> bool:
    for b in cls.bases:
        if isinstance(b, ast.Name) and b.id == "Processor":
            return True
        if isinstance(b, ast.Attribute) and b.attr == "Processor":
            return True
    return False


def _inspect_python(name: str, text: str) -> tuple[Kind, str, str, str, Problem | None]:
    """(kind, entry, title, description, problem) of a Python file."""
    in_lib = name.startswith(LIB + "/")
    try:
        try:
            tree = ast.parse(text, filename=name)
        except SystemError as exc:
            # CPython 3.11's spurious "AST constructor recursion depth mismatch" when
            # another thread parses at the same time (python/cpython#106905): once more
            if "recursion depth mismatch" not in str(exc):
                raise
            tree = ast.parse(text, filename=name)
    except SyntaxError as exc:
        kind: Kind = "library"
        if not in_lib:
            kind = "play" if _PY_PLAY_GUESS.search(text) else \
                "processor" if _PY_PROC_GUESS.search(text) else "library"
        msg = f"SyntaxError: {exc.msg}"
        return kind, "", "", "", Problem("import", msg, exc.lineno)
    title = description = ""
    play_entry = processor = ""
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name == "play":
            play_entry = play_entry or "function"
        elif isinstance(node, ast.ClassDef):
            if node.name == "Play":
                play_entry = "class"
            elif not processor and _derives_from_processor(node):
                processor = node.name
        else:
            t = _str_constant(node, "TITLE")
            if t is not None:
                title = t
            d = _str_constant(node, "DESCRIPTION")
            if d is not None:
                description = d
    if not description:
        doc = ast.get_docstring(tree)
        if doc:
            description = doc.strip().split("\n\n", 1)[0].replace("\n", " ")
    if in_lib:
        return "library", "", title, description, None
    if play_entry:
        return "play", play_entry, title, description, None
    if processor:
        return "processor", processor, title, description, None
    return "library", "", title, description, None


def _inspect_octave(name: str, text: str) -> tuple[Kind, str, str, str, Problem | None]:
    lines = text.splitlines()
    first = None
    for i, ln in enumerate(lines):
        s = ln.strip()
        if not s or s.startswith(("%", "#")):
            continue
        first = i
        break
    stem = name.rsplit("/", 1)[-1][:-2]
    if first is None:
        return "library", "", "", "", None
    m = _M_FUNCTION.match(lines[first])
    help_lines: list[str] = []
    for ln in lines[first + 1:]:
        s = ln.strip()
        if not s.startswith(("%", "#")):
            break
        help_lines.append(s.lstrip("%#").strip())
    if not help_lines:  # help text above the function line
        for ln in lines[:first]:
            s = ln.strip()
            if s.startswith(("%", "#")):
                help_lines.append(s.lstrip("%#").strip())
    help_lines = [h for h in help_lines if h]
    title = help_lines[0] if help_lines else ""
    description = " ".join(help_lines[1:])
    if name.startswith(LIB + "/") or m is None or m.group(1) != stem:
        return "library", "", title, description, None
    return "play", "octave", title, description, None


def inspect(team_dir: Path, name: str, data: bytes, stat: Stat) -> Found:
    """One file, from its bytes (never executed)."""
    language: Language = "python" if name.endswith(".py") else "octave"
    stem = name.rsplit("/", 1)[-1].rsplit(".", 1)[0]
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        return Found(name, team_dir / name, "library", language, None, "", "",
                     version_of(data), stat, "",
                     Problem("import", f"not UTF-8 text (byte {exc.start})"))
    if language == "python":
        kind, entry, title, description, problem = _inspect_python(name, text)
    else:
        kind, entry, title, description, problem = _inspect_octave(name, text)
    return Found(name, team_dir / name, kind, language, stem if kind == "play" else None,
                 title, description, version_of(data), stat, entry, problem)


def with_collisions(found: Mapping[str, Found], builtin: Iterable[str]) -> dict[str, Found]:
    """Marks plays whose name is a built-in play's or another play file's."""
    builtin = set(builtin)
    by_play: dict[str, list[str]] = {}
    for f in found.values():
        if f.play is not None:
            by_play.setdefault(f.play, []).append(f.name)
    out = {name: replace(f, clash="") if f.clash else f for name, f in found.items()}
    for play, names in by_play.items():
        for name in names:
            f = out[name]
            if play in builtin:
                msg = f"the play name {play!r} is a built-in play's: rename the file"
            elif len(names) > 1:
                others = ", ".join(n for n in names if n != name)
                msg = f"the play name {play!r} is also {others}'s: rename one of them"
            else:
                continue
            out[name] = replace(f, clash=msg)
    return out


def scan(team_dir: Path, builtin: Iterable[str],
         previous: Mapping[str, Found] | None = None,
         stats: Mapping[str, Stat] | None = None) -> dict[str, Found]:
    """Every team file; a file whose stat is unchanged since ``previous`` is not read again.
    ``stats``: the listing already taken (the watcher's), else listed here."""
    listing = list_files(team_dir) if stats is None else stats
    out: dict[str, Found] = {}
    for name, st in listing.items():
        old = previous.get(name) if previous else None
        if old is not None and old.stat == st:
            out[name] = old
            continue
        try:
            data = (team_dir / name).read_bytes()
        except OSError:
            continue  # removed between the listing and the read: the next scan sees it
        out[name] = inspect(team_dir, name, data, st)
    return with_collisions(out, builtin)
