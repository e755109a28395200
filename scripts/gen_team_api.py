"""Generates docs/team-api.md, the reference of the interface a team's code is written to,
from the ``touchline`` package itself (its classes, fields, types, defaults and the ``#:``
comments beside them, the Octave layouts), so the page and the code never disagree.

    python scripts/gen_team_api.py            # write docs/team-api.md
    python scripts/gen_team_api.py --check    # exit 1 if it is out of date (the tests do)
"""

from __future__ import annotations

import argparse
import ast
import io
import sys
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import touchline  # noqa: E402
from touchline import octave  # noqa: E402

OUT = ROOT / "docs" / "team-api.md"
PKG = ROOT / "touchline"


def _comments(src: str) -> dict[int, str]:
    """Line number -> the ``#:`` comment on it (or ``#`` after code on it)."""
    out: dict[int, str] = {}
    for tok in tokenize.generate_tokens(io.StringIO(src).readline):
        if tok.type == tokenize.COMMENT:
            text = tok.string.lstrip("#").lstrip(":").strip()
            out[tok.start[0]] = text
    return out


def _doc_for(lineno: int, end: int, comments: dict[int, str], lines: list[str]) -> str:
    """The comment of a field: ``#:`` lines right above it, then a comment on its lines."""
    above: list[str] = []
    k = lineno - 1
    while k >= 1 and lines[k - 1].strip().startswith("#"):
        above.insert(0, comments.get(k, ""))
        k -= 1
    beside = [comments[i] for i in range(lineno, end + 1) if i in comments
              and not lines[i - 1].strip().startswith("#")]
    return " ".join(x for x in [*above, *beside] if x)


def _cell(s: str) -> str:
    return s.replace("|", "\\|").replace("\n", " ")


def classes(module: str) -> list[str]:
    path = PKG / f"{module}.py"
    src = path.read_text()
    lines = src.splitlines()
    comments = _comments(src)
    tree = ast.parse(src)
    out: list[str] = []
    for node in tree.body:
        if not isinstance(node, ast.ClassDef) or node.name.startswith("_"):
            continue
        out.append(f"### `{node.name}`\n")
        doc = ast.get_docstring(node)
        if doc:
            out.append(doc.strip() + "\n")
        rows: list[str] = []
        members: list[str] = []
        for item in node.body:
            if isinstance(item, ast.AnnAssign) and isinstance(item.target, ast.Name):
                name = item.target.id
                default = "" if item.value is None else ast.unparse(item.value)
                if default.startswith("_field("):
                    default = "{}" if "dict" in default else default
                text = _doc_for(item.lineno, item.end_lineno or item.lineno, comments, lines)
                rows.append(f"| `{name}` | `{_cell(ast.unparse(item.annotation))}` | "
                            f"{'`' + _cell(default) + '`' if default else 'required'} | "
                            f"{_cell(text)} |")
            elif isinstance(item, ast.FunctionDef) and not item.name.startswith("_"):
                kind = "property" if any(isinstance(d, ast.Name) and d.id == "property"
                                         for d in item.decorator_list) else "method"
                args = ast.unparse(item.args).replace("self, ", "").replace("self", "")
                ret = f" -> {ast.unparse(item.returns)}" if item.returns else ""
                sig = f"{item.name}" if kind == "property" else f"{item.name}({args}){ret}"
                d = ast.get_docstring(item) or ""
                members.append(f"- `{sig}` ({kind}){': ' + d.strip() if d else ''}")
        if rows:
            out.append("| field | type | default | meaning |\n| --- | --- | --- | --- |")
            out.extend(rows)
            out.append("")
        if members:
            out.extend(members)
            out.append("")
    return out


def constants(module: str, names: list[str]) -> list[str]:
    """Module-level constants with their ``#:`` comments."""
    path = PKG / f"{module}.py"
    src = path.read_text()
    lines = src.splitlines()
    comments = _comments(src)
    out: list[str] = []
    for node in ast.parse(src).body:
        target = node.targets[0] if isinstance(node, ast.Assign) else \
            node.target if isinstance(node, ast.AnnAssign) else None
        if not (isinstance(target, ast.Name) and target.id in names):
            continue
        value = node.value
        if isinstance(value, ast.Subscript) and ast.unparse(value.value) == "Literal":
            # a Literal with a comment per value: a list of the values
            out.append(f"- `{target.id}`: one of")
            elts = value.slice.elts if isinstance(value.slice, ast.Tuple) else [value.slice]
            for e in elts:
                note = comments.get(e.lineno, "")
                out.append(f"  - `{ast.unparse(e)}`{': ' + note if note else ''}")
            continue
        text = _doc_for(node.lineno, node.end_lineno or node.lineno, comments, lines)
        out.append(f"- `{target.id}`: {text}")
    return out


def octave_section() -> list[str]:
    out = ["## Octave / MATLAB plays (`touchline/octave.py`)\n",
           (octave.__doc__ or "").strip(), ""]
    for title, cols in (("ours", octave.OURS_COLUMNS), ("theirs", octave.THEIRS_COLUMNS),
                        ("ball", octave.BALL_COLUMNS), ("orders (returned)",
                                                        octave.ORDER_COLUMNS)):
        out.append(f"`{title}`: " + " ".join(f"{i}:`{c}`" for i, c in enumerate(cols, 1)))
        out.append("")
    out.append("`game` (a struct): " + ", ".join(f"`{f}`" for f in octave.GAME_FIELDS))
    out.append("")
    out += constants("octave", ["OURS_COLUMNS", "THEIRS_COLUMNS", "BALL_COLUMNS",
                                "ORDER_COLUMNS", "GAME_FIELDS"])
    out.append("")
    return out


def render() -> str:
    parts = [
        "# The team-code interface (API version " + str(touchline.API_VERSION) + ")",
        "",
        "<!-- GENERATED by scripts/gen_team_api.py from the touchline package: do not edit. -->",
        "",
        (touchline.__doc__ or "").strip(),
        "",
        "How the station runs a team's code (files, reload, errors, the safety envelope, "
        "who may edit in the page): [team-code.md](team-code.md), "
        "[security.md](security.md).",
        "",
        "## The snapshot (`touchline/game.py`)",
        "",
        (sys.modules["touchline.game"].__doc__ or "").strip(),
        "",
        *constants("game", ["API_VERSION", "SituationName"]),
        "",
        *classes("game"),
        "## The orders (`touchline/orders.py`)",
        "",
        (sys.modules["touchline.orders"].__doc__ or "").strip(),
        "",
        *classes("orders"),
        *constants("orders", ["STOP"]),
        "",
        "## Processors (`touchline/processor.py`)",
        "",
        (sys.modules["touchline.processor"].__doc__ or "").strip(),
        "",
        *classes("processor"),
        *octave_section(),
        "## The library (`touchline/lib.py`)",
        "",
        (ast.get_docstring(ast.parse((PKG / "lib.py").read_text())) or "").strip(),
        "",
    ]
    text = "\n".join(parts)
    while "\n\n\n" in text:
        text = text.replace("\n\n\n", "\n\n")
    return text.rstrip() + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--check", action="store_true", help="fail if docs/team-api.md is stale")
    a = ap.parse_args()
    text = render()
    if a.check:
        if not OUT.exists() or OUT.read_text() != text:
            print(f"{OUT.relative_to(ROOT)} is out of date: run "
                  "python scripts/gen_team_api.py (make contract)")
            return 1
        return 0
    OUT.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
