"""The package's floors (docs/ARCHITECTURE.md "Layers"): data flows one way.

The table in docs/ARCHITECTURE.md is the one definition; this test reads it and walks
every ``import`` in the package with ``ast`` (top-level and inside functions alike, since
an import hidden in a function is still an arrow), so a move that breaks the layering,
or a new module nobody placed, fails here with the file and line.
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


def unit_of(module: str) -> str:
    """``station.plant.kernel`` -> ``plant``; ``station`` itself -> ``__init__``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def imports() -> list[tuple[str, str, str, int]]:
    """Every import of a station module: (importing unit, imported unit, file, line)."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(REPO)
        module = ".".join(rel.with_suffix("").parts).removesuffix(".__init__")
        src = unit_of(module)
        for node in ast.walk(ast.parse(path.read_text(), str(rel))):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                targets = [node.module]
                if node.module == "station":  # from station import plant, DT
                    targets = [f"station.{a.name}" for a in node.names]
            elif isinstance(node, ast.ImportFrom):  # relative: resolve against the package
                base = module.split(".")[: len(module.split(".")) - node.level + (path.name == "__init__.py")]
                targets = [".".join(base + ([node.module] if node.module else []))]
            else:
                continue
            for t in targets:
                if t == "station" or t.startswith("station."):
                    found.append((src, unit_of(t), str(rel), node.lineno))
    return found


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
