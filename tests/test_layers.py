"""The package's floors (docs/ARCHITECTURE.md "Layers"): data flows one way.

The table in docs/ARCHITECTURE.md is the one definition; this test reads it and walks
every ``import`` in the package with ``ast`` (top-level and inside functions alike, since
an import hidden in a function is still an arrow), so a move that breaks the layering,
or a new module nobody placed, fails here with the file and line. A package may also
list its rooms (sub-packages and modules) with their own order, as rows ``| 7.1 |
`diagnosis.runs/` |``: a room imports only from its own order or below.

Module by module, there is no circle (inside a package too), no module is over 600 lines,
and no import hides in a function unless it is a documented lazy import: ``# lazy: why`` on
its line or on the line above its block of imports (start-up time: the CLI's parser and a
step's first tick must not wait for scipy, python-control, matplotlib or numba).
"""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / "station"
ARCHITECTURE = REPO / "docs" / "ARCHITECTURE.md"


def floors() -> dict[str, int]:
    """Unit (a top-level module or subpackage of station) -> its floor, from the table."""
    out: dict[str, int] = {}
    for line in ARCHITECTURE.read_text().splitlines():
        m = re.match(r"\|\s*(\d+)\s*\|(.*?)\|", line)
        if not m:
            continue
        for name in re.findall(r"`([A-Za-z_]+)/?`", m.group(2)):
            out[name] = int(m.group(1))
    return out


def rooms() -> dict[str, dict[str, float]]:
    """Package -> its room (a sub-package or module) -> its order, from rows ``| 7.1 | `pkg.room/` |``."""
    out: dict[str, dict[str, float]] = defaultdict(dict)
    for line in ARCHITECTURE.read_text().splitlines():
        m = re.match(r"\|\s*(\d+\.\d+)\s*\|(.*?)\|", line)
        if not m:
            continue
        for pkg, room in re.findall(r"`([A-Za-z_]+)\.([A-Za-z_]+)/?`", m.group(2)):
            out[pkg][room] = float(m.group(1))
    return dict(out)


def module_of(path: Path) -> str:
    """``station/plant/kernel.py`` -> ``station.plant.kernel``; a package's ``__init__`` -> the package."""
    return ".".join(path.relative_to(REPO).with_suffix("").parts).removesuffix(".__init__")


MODULES = {module_of(p) for p in PACKAGE.rglob("*.py")}


def resolve(node: ast.Import | ast.ImportFrom, module: str, is_package: bool) -> list[str]:
    """The modules an import statement names: ``from a.b import c`` is ``a.b.c`` when that is
    a module, else ``a.b``; relative imports are resolved against ``module``."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if node.level:
        parts = module.split(".")
        base = parts[: len(parts) - node.level + is_package]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in MODULES]
    return subs + ([target] if len(subs) < len(node.names) else [])


def module_imports() -> list[tuple[str, str, str, int, bool]]:
    """Every import of a station module: (importing module, imported module, file, line,
    inside a function)."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel, module = path.relative_to(REPO), module_of(path)
        tree = ast.parse(path.read_text(), str(rel))
        in_function = {id(n) for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
                       for n in ast.walk(f) if isinstance(n, (ast.Import, ast.ImportFrom))}
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                for t in resolve(node, module, path.name == "__init__.py"):
                    if t == "station" or t.startswith("station."):
                        found.append((module, t, str(rel), node.lineno, id(node) in in_function))
    return found


def unit_of(module: str) -> str:
    """``station.plant.kernel`` -> ``plant``; ``station`` itself -> ``__init__``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def imports() -> list[tuple[str, str, str, int]]:
    """Every import of a station module: (importing unit, imported unit, file, line)."""
    return [(unit_of(src), unit_of(dst), file, line) for src, dst, file, line, _ in module_imports()]


def test_the_table_is_read():
    table = floors()
    # a few anchors, so a reformatted table cannot make every check below vacuous
    assert table["errors"] == 1 and table["plant"] == 3 and table["commands"] == max(table.values())
    assert len(table) >= 30


def test_every_unit_has_a_floor():
    table = floors()
    units = {p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__"}
    units |= {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()}
    missing = sorted(units - set(table))
    assert not missing, f"not placed in docs/ARCHITECTURE.md's floor table: {', '.join(missing)}"


def test_no_import_runs_up_a_floor():
    table = floors()
    up = []
    for src, dst, file, line in imports():
        if src == dst or dst == "__init__" or src == "__init__":
            continue  # within a unit; the package's own constants (DT, __version__) are floor 0
        if dst in table and src in table and table[dst] > table[src]:
            up.append(f"{file}:{line}: {src} (floor {table[src]}) imports {dst} (floor {table[dst]})")
    assert not up, "imports that run up the layers:\n" + "\n".join(up)


def test_nothing_but_cli_imports_commands():
    bad = [f"{file}:{line}: {src}" for src, dst, file, line in imports()
           if dst == "commands" and src not in ("commands", "cli")]
    assert not bad, "only station.cli imports station.commands:\n" + "\n".join(bad)


def test_no_circle_between_units():
    graph: dict[str, set[str]] = defaultdict(set)
    for src, dst, _, _ in imports():
        if src != dst and "__init__" not in (src, dst):
            graph[src].add(dst)

    def reaches(a: str, b: str) -> bool:
        seen, todo = set(), [a]
        while todo:
            n = todo.pop()
            if n == b:
                return True
            if n not in seen:
                seen.add(n)
                todo.extend(graph.get(n, ()))
        return False

    circles = sorted({tuple(sorted((a, b))) for a in list(graph) for b in graph[a] if reaches(b, a)})
    assert not circles, f"units that import each other (directly or through others): {circles}"


@pytest.mark.parametrize("name", ["station.plant.kernel", "station.diagnosis.search.selection"])
def test_unit_of(name):
    assert unit_of(name) == name.split(".")[1]


def test_the_rooms_are_read():
    table = rooms()
    # anchors: the diagnosis's bottom and top rooms, so a reformatted table cannot make the checks vacuous
    assert table["diagnosis"]["runs"] < table["diagnosis"]["search"] < table["diagnosis"]["honesty"] \
        < table["diagnosis"]["answer"] < table["diagnosis"]["identify"]


def test_every_module_of_a_package_with_rooms_has_a_room():
    missing = []
    for pkg, table in rooms().items():
        for module in sorted(MODULES):
            parts = module.split(".")
            if len(parts) > 2 and parts[1] == pkg and parts[2] not in table:
                missing.append(module)
    assert not missing, f"not placed in docs/ARCHITECTURE.md's rooms: {', '.join(missing)}"


def test_no_import_runs_up_a_room():
    up = []
    for pkg, table in rooms().items():
        for src, dst, file, line, _ in module_imports():
            s, d = src.split("."), dst.split(".")
            if len(s) > 2 and len(d) > 2 and s[1] == d[1] == pkg and s[2] != d[2]:
                if table.get(d[2], 0) > table.get(s[2], 0):
                    up.append(f"{file}:{line}: {pkg}.{s[2]} ({table[s[2]]}) imports {pkg}.{d[2]} ({table[d[2]]})")
    assert not up, "imports that run up a package's rooms:\n" + "\n".join(up)


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The graph's strongly connected components of more than one node (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_circles_finds_a_circle_through_three_modules():
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": {"c"}}) == []


def test_no_circle_between_modules():
    """Module by module, inside a package too (the diagnosis's doubt -> selection -> prose ->
    doubt was one), an import inside a function counting like any other."""
    graph: dict[str, set[str]] = defaultdict(set)
    for src, dst, _, _, _ in module_imports():
        if src != dst:
            graph[src].add(dst)
    found = circles(graph)
    assert not found, "modules that import each other (directly or through others):\n" + "\n".join(
        " <-> ".join(c) for c in found)


LAZY = re.compile(r"#\s*lazy:\s*\S")


def hidden_imports(path: Path, root: Path = REPO) -> list[str]:
    """The imports inside ``path``'s functions without a ``# lazy: why`` comment on their
    line or on the line above their block of imports."""
    lines = path.read_text().splitlines()
    tree = ast.parse("\n".join(lines))
    found = []
    for f in ast.walk(tree):
        if not isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        nodes = [n for n in ast.walk(f) if isinstance(n, (ast.Import, ast.ImportFrom))]
        ends = {n.end_lineno: n for n in nodes}
        for n in nodes:
            if any(LAZY.search(lines[i - 1]) for i in range(n.lineno, n.end_lineno + 1)):
                continue
            above = n.lineno - 1
            while above in ends:  # up the block of imports
                above = ends[above].lineno - 1
            if above >= 1 and LAZY.search(lines[above - 1]) and lines[above - 1].strip().startswith("#"):
                continue
            found.append(f"{path.relative_to(root)}:{n.lineno}: {lines[n.lineno - 1].strip()}")
    return sorted(set(found))


def test_no_import_hides_in_a_function():
    hidden = [h for p in sorted(PACKAGE.rglob("*.py")) for h in hidden_imports(p)]
    assert not hidden, ("imports inside functions without a '# lazy: why' comment (hoist them, or say why "
                        "they wait):\n" + "\n".join(hidden))


def test_hidden_imports_are_found(tmp_path):
    src = tmp_path / "m.py"
    src.write_text("import os\n\n\ndef f():\n    import json\n    # lazy: start-up time (scipy)\n"
                   "    import scipy\n    from scipy import signal\n\n    x = 1\n    import re  # lazy: start-up time\n"
                   "    import math\n")
    assert [h.split(":")[1] for h in hidden_imports(src, tmp_path)] == ["12", "5"]


MAX_LINES = 600
"""Longest module, lines (the developers' guide: small modules, one job each)."""


def long_modules(root: Path = PACKAGE, limit: int = MAX_LINES) -> list[str]:
    """The modules under ``root`` longer than ``limit`` lines, ``path: N lines`` each."""
    out = []
    for path in sorted(root.rglob("*.py")):
        n = len(path.read_text().splitlines())
        if n > limit:
            out.append(f"{path.relative_to(root.parent)}: {n} lines")
    return out


def test_long_modules_are_found(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "short.py").write_text("x = 1\n" * 600)
    (pkg / "long.py").write_text("x = 1\n" * 601)
    assert long_modules(pkg) == ["pkg/long.py: 601 lines"]


def test_no_module_is_over_600_lines():
    """Split a module that grows past it by idea (the diagnosis's rooms show how), not in halves."""
    found = long_modules()
    assert not found, f"modules over {MAX_LINES} lines:\n" + "\n".join(found)
