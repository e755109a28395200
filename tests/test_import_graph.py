"""The structure's import rules, read from the source (no module is imported): no module imports
another in a circle, no package imports another in a circle, and the lower packages (the log
format, the domain, the network helpers) never reach up into the backend or any other.

The graph is the modules' own ``import`` statements at module level, those under
``if TYPE_CHECKING:`` included (a type named in a signature is a dependency a reader must
follow just the same). Imports inside a function are left out of the circle check (they are
how a command or a late start loads what it needs) but not of the "lower packages" rule: a
lower package reaching the backend from inside a function reaches it all the same."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: the first-party packages (every top-level folder with Python code but the generated
#: protobuf code, the tests, the benchmarks, the experiments and the scripts)
_NOT_CHECKED = {"sslpb", "tests", "bench", "experiments", "scripts", "node_modules",
                "frontend", "e2e", "proto", "docs", "var"}
#: the lower packages: leaves the others build on, importing none of them (but each other)
_LOWER = ("ssllog", "domain", "sslnet")
#: modules that sit in a package's folder for their import path but above the backend, so
#: they count as packages of their own (and nothing first-party may import them): the team
#: API's library lends a team's plays the backend's geometry, roles and path planner, while
#: the backend's team-code host imports the API's types (``touchline``) it hands to plays
_ON_TOP = {"touchline.lib": "the team's library of the backend's own strategy pieces"}


def packages() -> list[str]:
    return sorted(p.name for p in ROOT.iterdir()
                  if p.is_dir() and (p / "__init__.py").exists() and p.name not in _NOT_CHECKED)


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute name of a ``from X import`` (relative ones against ``module``)."""
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    if not is_package:
        base.pop()
    if node.level > 1:
        base = base[: len(base) - (node.level - 1)]
    return ".".join([*base, node.module] if node.module else base)


def _imports(tree: ast.Module, module: str, is_package: bool,
             top_only: bool) -> Iterator[tuple[str, list[str]]]:
    """(module imported, names imported from it) of each import statement; ``top_only``:
    those at module level (and in module-level ``if``/``try`` blocks) only."""
    def walk(body: list[ast.stmt]) -> Iterator[ast.stmt]:
        for stmt in body:
            yield stmt
            if isinstance(stmt, ast.If | ast.Try):
                yield from walk(stmt.body)
                yield from walk(stmt.orelse)
                if isinstance(stmt, ast.Try):
                    for h in stmt.handlers:
                        yield from walk(h.body)
                    yield from walk(stmt.finalbody)

    stmts = walk(tree.body) if top_only else ast.walk(tree)
    for node in stmts:
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, []
        elif isinstance(node, ast.ImportFrom):
            yield _resolve(module, is_package, node), [a.name for a in node.names]


def import_graph(top_only: bool = True) -> dict[str, set[str]]:
    """Module -> the first-party modules it imports. ``from pkg import name`` counts as an
    import of ``pkg.name`` when that is a module, else of ``pkg``."""
    files: dict[str, Path] = {}
    for pkg in packages():
        for path in (ROOT / pkg).rglob("*.py"):
            if "node_modules" not in path.parts:
                files[_module_name(path)] = path
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        tree = ast.parse(path.read_text(), str(path))
        is_package = path.name == "__init__.py"
        deps: set[str] = set()
        for target, names in _imports(tree, name, is_package, top_only):
            subs = [f"{target}.{n}" for n in names if f"{target}.{n}" in files]
            if subs:
                deps.update(subs)
            if len(subs) < len(names) or not names:
                # the module itself (or its package, for ``import a.b.c`` of a non-module)
                while target and target not in files:
                    target = target.rpartition(".")[0]
                if target:
                    deps.add(target)
        deps.discard(name)
        graph[name] = deps
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one member (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        # iterative: the graph is deep enough to matter for Python's recursion limit
        work: list[tuple[str, Iterator[str]]] = [(v, iter(sorted(graph.get(v, ()))))]
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        while work:
            node, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                    break
                if w in on_stack:
                    low[node] = min(low[node], index[w])
            else:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[node])
                if low[node] == index[node]:
                    comp: list[str] = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        comp.append(w)
                        if w == node:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def _package_of(module: str) -> str:
    return module if module in _ON_TOP else module.split(".")[0]


def _package_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    out: dict[str, set[str]] = {}
    for m, deps in graph.items():
        top = _package_of(m)
        out.setdefault(top, set()).update(_package_of(d) for d in deps)
        out[top].discard(top)
    return out


def test_the_graph_sees_the_imports_it_must() -> None:
    """The reader itself: a known edge of each kind is found (a broken reader would find no
    circle anywhere), and the circle finder finds a circle."""
    g = import_graph()
    assert "backend.bus" in g["backend.station"]  # from .bus import DataBus
    assert "backend.contract" in g["backend.views"]  # from . import contract, topics
    assert "backend.topics" in g["backend.bus"]  # under TYPE_CHECKING
    assert "ssllog.logfile" not in g["backend.replay.logs"]  # inside a function ...
    assert "ssllog.logfile" in import_graph(top_only=False)["backend.replay.logs"]  # ... seen
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set()}) == []


def test_no_module_imports_another_in_a_circle() -> None:
    found = circles(import_graph())
    assert found == [], "modules importing each other in a circle:\n" + "\n".join(
        " <-> ".join(c) for c in found)


def test_no_package_imports_another_in_a_circle() -> None:
    found = circles(_package_graph(import_graph()))
    assert found == [], f"packages importing each other in a circle: {found}"


def test_what_sits_on_top_is_imported_by_nothing() -> None:
    """A module counted as a package of its own above the backend (``_ON_TOP``) stays on
    top: no first-party module imports it (the team's plays do, from their own folder)."""
    graph = import_graph(top_only=False)
    bad = sorted(f"{m} -> {d}" for m, deps in graph.items() for d in deps
                 if d in _ON_TOP and m != d)
    assert bad == [], "imports of a module that must stay on top:\n" + "\n".join(bad)


def test_lower_packages_do_not_import_the_backend() -> None:
    """The log format, the domain and the network helpers are leaves the backend (and the
    relay, fieldsim, the match) build on; an import the other way, even inside a function,
    would make them need what they serve."""
    graph = import_graph(top_only=False)
    bad = sorted(f"{m} -> {d}" for m, deps in graph.items()
                 if m.split(".")[0] in _LOWER
                 for d in deps if d.split(".")[0] not in _LOWER)
    assert bad == [], "lower packages importing an upper one:\n" + "\n".join(bad)
