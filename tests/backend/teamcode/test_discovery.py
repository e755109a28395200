"""The team folder is read, never run, in the station's process: what each file is comes
from its syntax tree (Python) or its first function line (Octave)."""

from __future__ import annotations

import os
from pathlib import Path

from backend.params.model import PLAYS
from backend.teamcode.discovery import inspect, list_files, scan
from backend.teamcode.registry import TeamRegistry
from backend.teamcode.watcher import FolderWatcher

ROOT = Path(__file__).resolve().parents[3]


def write(folder: Path, name: str, text: str) -> Path:
    p = folder / name
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    return p


def test_the_kinds_of_python_file(tmp_path: Path) -> None:
    write(tmp_path, "pass_drill.py", 'TITLE = "Pass drill"\nDESCRIPTION = "two robots"\n'
                                     "def play(game):\n    return {}\n")
    write(tmp_path, "stateful.py", '"""A play as a class.\n\nMore."""\nclass Play:\n'
                                   "    def tick(self, game):\n        return {}\n")
    write(tmp_path, "possession.py", "from touchline import Processor\n"
                                     "class Helper:\n    pass\n"
                                     "class Possession(Processor):\n    pass\n")
    write(tmp_path, "qualified.py", "import touchline\n"
                                    "class P(touchline.Processor):\n    pass\n")
    write(tmp_path, "util.py", "def helper():\n    return 1\n")
    write(tmp_path, "lib/geometry2.py", "def play(game):\n    return {}\n")
    found = scan(tmp_path, PLAYS)
    assert sorted(found) == ["lib/geometry2.py", "pass_drill.py", "possession.py",
                             "qualified.py", "stateful.py", "util.py"]
    f = found["pass_drill.py"]
    assert (f.kind, f.language, f.play, f.entry, f.title, f.description) == \
        ("play", "python", "pass_drill", "function", "Pass drill", "two robots")
    f = found["stateful.py"]
    assert (f.kind, f.play, f.entry, f.description) == ("play", "stateful", "class",
                                                        "A play as a class.")
    assert (found["possession.py"].kind, found["possession.py"].entry) == \
        ("processor", "Possession")
    assert (found["qualified.py"].kind, found["qualified.py"].entry) == ("processor", "P")
    assert found["util.py"].kind == "library" and found["util.py"].play is None
    # lib/ holds libraries only, whatever they define
    assert found["lib/geometry2.py"].kind == "library"
    assert all(f.error is None for f in found.values())


def test_nothing_is_executed(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    write(tmp_path, "evil.py", f"open({str(marker)!r}, 'w').write('x')\n"
                               "def play(game):\n    return {}\n")
    found = scan(tmp_path, PLAYS)
    assert found["evil.py"].kind == "play"
    assert not marker.exists()


def test_a_file_that_does_not_parse_is_an_import_error_with_its_line(tmp_path: Path) -> None:
    write(tmp_path, "broken.py", "def play(game):\n    return {\n\nx = = 1\n")
    write(tmp_path, "bad_proc.py", "class P(Processor):\n  def tick(self\n")
    write(tmp_path, "latin1.py", "")
    (tmp_path / "latin1.py").write_bytes(b"# caf\xe9\ndef play(g):\n    return {}\n")
    found = scan(tmp_path, PLAYS)
    b = found["broken.py"]
    assert b.kind == "play" and b.play == "broken"  # still a play: chosen, it fails
    assert b.error is not None and b.error.kind == "import"
    assert b.error.message.startswith("SyntaxError") and b.error.line in (2, 4)
    assert found["bad_proc.py"].kind == "processor"
    assert found["latin1.py"].error is not None
    assert "UTF-8" in found["latin1.py"].error.message


def test_octave_files(tmp_path: Path) -> None:
    write(tmp_path, "keeper.m", "% leading comment\n"
                                "function orders = keeper(ours, theirs, ball, game)\n"
                                "  % Keeper only\n  % stands on the line\n  orders = [];\nend\n"
                                "function y = helper(x)\n  y = x;\nend\n")
    write(tmp_path, "helpers.m", "function y = other_name(x)\n  y = x;\nend\n")
    write(tmp_path, "script.m", "x = 1;\n")
    write(tmp_path, "lib/lib_play.m", "function orders = lib_play(a, b, c, d)\nend\n")
    found = scan(tmp_path, PLAYS)
    k = found["keeper.m"]
    assert (k.kind, k.language, k.play, k.entry, k.title, k.description) == \
        ("play", "octave", "keeper", "octave", "Keeper only", "stands on the line")
    assert found["helpers.m"].kind == "library"
    assert found["script.m"].kind == "library"
    assert found["lib/lib_play.m"].kind == "library"


def test_play_names_that_clash(tmp_path: Path) -> None:
    write(tmp_path, "match.py", "def play(game):\n    return {}\n")  # a built-in play's
    write(tmp_path, "twin.py", "def play(game):\n    return {}\n")
    write(tmp_path, "twin.m", "function orders = twin(a, b, c, d)\nend\n")
    write(tmp_path, "alone.py", "def play(game):\n    return {}\n")
    reg = TeamRegistry(tmp_path, PLAYS)
    reg.rescan()
    found = reg.found
    assert found["match.py"].error is not None
    assert "built-in" in found["match.py"].error.message
    assert "twin.m" in found["twin.py"].error.message  # type: ignore[union-attr]
    assert "twin.py" in found["twin.m"].error.message  # type: ignore[union-attr]
    assert found["alone.py"].error is None
    assert set(reg.plays()) == {"alone"}
    # the clash goes when the other file goes
    os.unlink(tmp_path / "twin.m")
    assert reg.rescan() == {"twin.m", "twin.py"}
    assert reg.found["twin.py"].error is None and set(reg.plays()) == {"alone", "twin"}
    view = {f["name"]: f for f in reg.files_view()}
    assert view["match.py"]["state"] == "error"
    assert view["match.py"]["error"]["kind"] == "import"  # type: ignore[index]


def test_only_team_file_names_are_listed(tmp_path: Path) -> None:
    for name in ("ok.py", "ok2.m", ".hidden.py", "x.py~", ".x.py.swp", "#x.py#", "1bad.py",
                 "with-dash.py", "notes.txt", "lib/inlib.py", "other/deep.py",
                 ".ok.py.abc123.tmp"):
        write(tmp_path, name, "x = 1\n")
    (tmp_path / "dir.py").mkdir()
    assert list(list_files(tmp_path)) == ["lib/inlib.py", "ok.py", "ok2.m"]
    assert list_files(tmp_path / "missing") == {}


def test_the_version_is_the_content(tmp_path: Path) -> None:
    p = write(tmp_path, "a.py", "def play(g):\n    return {}\n")
    st = list_files(tmp_path)["a.py"]
    v1 = inspect(tmp_path, "a.py", p.read_bytes(), st).version
    p.write_text("def play(g):\n    return {1: None}\n")
    v2 = inspect(tmp_path, "a.py", p.read_bytes(), st).version
    assert v1 != v2 and len(v1) == 12 and int(v1, 16) >= 0


def test_the_watcher_sees_saves_additions_and_removals(tmp_path: Path) -> None:
    seen: list[dict[str, object]] = []
    w = FolderWatcher(tmp_path, lambda listing: seen.append(dict(listing)))
    p = write(tmp_path, "a.py", "def play(g):\n    return {}\n")
    w.last = list_files(tmp_path)  # as at start
    assert not w.poll() and seen == []
    st = p.stat()
    p.write_text("def play(g):\n    return {1: 2}\n")  # a save (size changes)
    os.utime(p, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))
    assert w.poll() and list(seen[-1]) == ["a.py"]
    write(tmp_path, "lib/b.m", "x = 1;\n")
    assert w.poll() and list(seen[-1]) == ["a.py", "lib/b.m"]
    os.unlink(p)
    assert w.poll() and list(seen[-1]) == ["lib/b.m"]
    assert not w.poll()


def test_a_save_in_place_with_the_same_size_is_seen(tmp_path: Path) -> None:
    """Same size, same inode: the modification time tells."""
    p = write(tmp_path, "a.py", "A = 1\n")
    w = FolderWatcher(tmp_path, lambda _listing: None)
    w.last = list_files(tmp_path)
    st = p.stat()
    p.write_text("A = 2\n")
    os.utime(p, ns=(st.st_atime_ns, st.st_mtime_ns + 1))
    assert w.poll()


def test_the_registry_tells_what_changed(tmp_path: Path) -> None:
    write(tmp_path, "a.py", "def play(g):\n    return {}\n")
    reg = TeamRegistry(tmp_path, PLAYS)
    heard: list[set[str]] = []
    reg.listeners.append(lambda changed, _found: heard.append(changed))
    assert reg.rescan() == {"a.py"}
    assert reg.rescan() == set()  # nothing new: no one told
    p = tmp_path / "a.py"
    st = p.stat()
    p.write_text("def play(g):\n    return {}\n")  # the same bytes again: no change
    os.utime(p, ns=(st.st_atime_ns, st.st_mtime_ns + 5))
    assert reg.rescan() == set()
    write(tmp_path, "lib/u.py", "X = 1\n")
    assert reg.rescan() == {"lib/u.py"}
    assert heard == [{"a.py"}, {"lib/u.py"}]


def test_the_shipped_team_folder(tmp_path: Path) -> None:
    found = scan(ROOT / "team", PLAYS)
    kinds = {(f.kind, f.language) for f in found.values() if f.error is None}
    assert {("play", "python"), ("play", "octave"), ("processor", "python")} <= kinds
    assert all(f.error is None for f in found.values())
