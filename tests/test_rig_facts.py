"""The rig's facts have one home, :mod:`station.rig` (issue 23): no literal copy in code.

An AST walk over station/ and scripts/ (docstrings and comments are text, not code, and may
say "0.002 s") fails on:

- the literal 0.002 anywhere in code;
- 500 used as a rate: an ``fs=``/``rate=`` argument or default, a name for a rate bound to
  it, a division by it;
- a fact's value bound to a name that says which fact it is: an assignment, a dataclass
  field, a parameter's default or a keyword argument (``limit=200.0``, ``at_tick=10``,
  ``soft_limit=2048.0``, ``timeout=0.1``, ``BAND = 0.02``, ``MAX_SAMPLES = 20_000``, ...);
- a second definition of a name :mod:`station.rig` defines.

Tests may use literals (they check against independent truth).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import station
from station import rig

REPO = Path(__file__).resolve().parents[1]
HOME = REPO / "station" / "rig.py"

FACTS = [  # (value, the names that mean this fact (case-insensitive), also as a call's keyword argument)
    (rig.RATE_HZ, r"rate|(^|_)hz$|^fs$", True),
    (rig.COUNTS_PER_REV, r"counts|per_rev|encoder", True),
    (rig.DAC_LIMIT, r"dac|v_limit", True),
    (rig.CLAMP, r"limit|clamp", True),
    (rig.DEFAULT_SOFT_LIMIT, r"soft_limit|limit", True),
    (rig.DEFAULT_TIMEOUT, r"timeout", True),
    (rig.DEFAULT_STEP_TICK, r"step_tick|at_tick|start_tick", True),
    # a step's height and length passed to a call are the caller's choice; defined, they are the defaults
    (rig.DEFAULT_AMPLITUDE, r"amplitude", False),
    (rig.DEFAULT_DURATION, r"duration|run_s$", False),
    (rig.THESIS_BAND, r"band", True),
    (rig.STEP_INFO_BAND, r"band", True),
    (rig.RESIDUAL_AFTER_S, r"residual|after_s", True),
    (rig.DIAGNOSE_MAX_SAMPLES, r"max_samples", True),
    (rig.SESSIONS_MAX_SAMPLES, r"max_samples", True),
]

FACT_NAMES = {name for name in vars(rig) if name.isupper()}


def code_files() -> list[Path]:
    return sorted((REPO / "station").rglob("*.py")) + sorted((REPO / "scripts").glob("*.py"))


def _number(node) -> float | None:
    """The value of a numeric literal (a negative one too), else None."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        inner = _number(node.operand)
        return None if inner is None else -inner
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        return float(node.value)
    return None


def _bindings(tree: ast.AST):
    """(name, value node, line, in a call) of every place a value is bound to a name:
    assignments, annotated assignments (dataclass fields), parameters' defaults and a call's
    keyword arguments."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    yield target.id, node.value, node.lineno, False
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and node.value is not None:
            yield node.target.id, node.value, node.lineno, False
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            a = node.args
            positional = a.posonlyargs + a.args
            for arg, default in zip(positional[len(positional) - len(a.defaults):], a.defaults):
                yield arg.arg, default, default.lineno, False
            for arg, default in zip(a.kwonlyargs, a.kw_defaults):
                if default is not None:
                    yield arg.arg, default, default.lineno, False
        elif isinstance(node, ast.Call):
            for kw in node.keywords:
                if kw.arg is not None:
                    yield kw.arg, kw.value, kw.value.lineno, True


def fact_literals(source: str, name: str = "<source>") -> list[str]:
    """Where ``source`` writes one of the rig's facts as a literal, or defines a name that
    :mod:`station.rig` defines, one line each (``name:line: what``)."""
    tree = ast.parse(source)
    found = []
    for node in ast.walk(tree):
        value = _number(node)
        if value == rig.DT:
            found.append(f"{name}:{node.lineno}: the literal 0.002 (station.rig.DT)")
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div) and _number(node.right) == rig.RATE_HZ:
            found.append(f"{name}:{node.lineno}: a division by 500 (station.rig.RATE_HZ or DT)")
    for bound, value_node, line, in_call in _bindings(tree):
        value = _number(value_node)
        if value is not None:
            for fact, names, calls in FACTS:
                if value == fact and re.search(names, bound, re.I) and (calls or not in_call):
                    found.append(f"{name}:{line}: {bound} = {value:g}: a fact of station.rig")
                    break
        if bound in FACT_NAMES and isinstance(value_node, (ast.Constant, ast.UnaryOp, ast.BinOp, ast.Dict, ast.Call)):
            found.append(f"{name}:{line}: {bound} defined again (station.rig.{bound})")
    return sorted(set(found))


@pytest.mark.parametrize("path", code_files(), ids=lambda p: str(p.relative_to(REPO)))
def test_no_fact_is_written_twice(path):
    if path == HOME:
        return
    found = fact_literals(path.read_text(), str(path.relative_to(REPO)))
    assert not found, "the rig's facts belong to station/rig.py:\n" + "\n".join(found)


@pytest.mark.parametrize("source, expected", [
    ("def f(dt: float = 0.002): pass", 1),
    ("t = n * 0.002", 1),
    ("y = scipy.signal.butter(4, 60, fs=500.0)", 1),
    ("def noise(x, fs: float = 500.0): pass", 1),
    ("RATE_HZ = 500", 2),                       # a fact's value under its name, and rig's name again
    ("period = 1.0 / 500", 1),
    ("def p(kp=2.0, limit: float | None = 200.0): pass", 1),
    ("RIG_LIMIT = 200.0", 1),
    ("make_controller('lead', limit=200.0)", 1),
    ("u = step_reference(50, n, at_tick=10)", 1),
    ("def run(soft_limit: float = 2048.0, timeout: float = 0.1): pass", 2),
    ("BAND = 0.02", 1),
    ("MAX_SAMPLES = 20_000", 1),
    ("RESIDUAL_AFTER_S = 0.6", 2),
    ("def step(amplitude=100.0, duration=2.0): pass", 2),
    ("COUNTS_PER_REV = 1024", 2),
    ("DT = 1.0 / RATE_HZ", 1),                  # rig's name defined again
    # not the facts: other numbers, other meanings, docstrings
    ('"""Sample time 0.002 s, 500 Hz, the clamp ±200."""', 0),
    ("def device(v_limit: int = int(DAC_LIMIT), watchdog_ticks: int = 10): pass", 0),
    ("steps = (50, 100, 200); MAX_ORDER = 20; lw = 0.6; STEP = step_reference(200.0, 1000)", 0),
    ("from station.rig import DT, CLAMP\nlimit = CLAMP", 0),
    ("run_step(controller='lead', amplitude=100, duration=2.0)", 0),  # a caller's choice
])
def test_the_walk_finds_the_facts(source, expected):
    assert len(fact_literals(source)) == expected, fact_literals(source)


def test_the_home_defines_each_fact_once():
    tree = ast.parse(HOME.read_text())
    names = [t.id for n in tree.body if isinstance(n, (ast.Assign, ast.AnnAssign))
             for t in (n.targets if isinstance(n, ast.Assign) else [n.target]) if isinstance(t, ast.Name)]
    assert len(names) == len(set(names)) and set(names) == FACT_NAMES


def test_the_facts_are_design_md_s():
    """Against DESIGN.md "The rig" and "Station defaults" (independent of the code)."""
    assert station.DT is rig.DT == 0.002 and rig.RATE_HZ == 500 and rig.RATE_HZ * rig.DT == 1.0
    assert rig.COUNTS_PER_RAD == pytest.approx(1024 / (2 * 3.141592653589793), rel=1e-15)
    assert (rig.DAC_LIMIT, rig.CLAMP, rig.DEFAULT_SOFT_LIMIT, rig.DEFAULT_TIMEOUT) == (255, 200, 2048, 0.1)
    assert (rig.DEFAULT_AMPLITUDE, rig.DEFAULT_STEP_TICK, rig.DEFAULT_DURATION) == (100, 10, 2.0)
    assert dict(rig.THESIS_STEPS) == {"p": 50, "lead": 100, "lead-accel": 200}
    assert (rig.THESIS_BAND, rig.THESIS_BAND_FLOOR, rig.STEP_INFO_BAND, rig.RESIDUAL_AFTER_S) == (0.01, 1, 0.02, 0.6)
