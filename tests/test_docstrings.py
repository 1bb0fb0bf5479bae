"""Docstrings stay true: every public function's parameters are documented, and nothing else is.

As python-control's ``control/tests/docstrings_test.py``: numpydoc's docscrape parses each
public function, method and class of the ``station`` package; each parameter of the
signature must appear in its Parameters (or Other Parameters) section, and every name there
must be a parameter. A class documents its constructor's parameters in its own docstring;
a dataclass or NamedTuple may list its fields as Attributes instead. ``self``/``cls`` are
exempt; ``*args``/``**kwargs`` are documented as such.

Every public function of ``station.diagnosis`` and ``station.design`` that returns or yields a
value says what in a Returns (or Yields) section, and the entry points' Examples run.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import pathlib
import pkgutil
import re
import warnings

import pytest
from numpydoc import docscrape  # in the test extras (pyproject.toml)

import station


def _public_modules():
    for info in pkgutil.walk_packages(station.__path__, "station."):
        if not any(part.startswith("_") for part in info.name.split(".")[1:]):
            yield importlib.import_module(info.name)


def _is_record(cls) -> bool:
    """A dataclass or NamedTuple: its fields are its constructor's parameters."""
    return dataclasses.is_dataclass(cls) or (issubclass(cls, tuple) and hasattr(cls, "_fields"))


def _callables():
    """(qualified name, function, docstring, skip first parameter, is a record's constructor)."""
    for mod in _public_modules():
        for name, obj in vars(mod).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != mod.__name__:
                continue
            if inspect.isfunction(obj):
                yield f"{mod.__name__}.{name}", obj, obj.__doc__, False, False
            elif inspect.isclass(obj):
                record = _is_record(obj)
                init = obj.__new__ if record and issubclass(obj, tuple) else obj.__dict__.get("__init__")
                if getattr(obj, "_is_protocol", False):
                    init = None  # typing's stand-in __init__: a Protocol is a type, never instantiated
                if init is not None and inspect.isfunction(init):
                    yield f"{mod.__name__}.{name}", init, obj.__doc__, True, record
                for attr, member in obj.__dict__.items():
                    if attr.startswith("_"):
                        continue
                    if isinstance(member, (staticmethod, classmethod)):
                        yield (f"{mod.__name__}.{name}.{attr}", member.__func__, member.__func__.__doc__,
                               isinstance(member, classmethod), False)
                    elif inspect.isfunction(member):
                        yield f"{mod.__name__}.{name}.{attr}", member, member.__doc__, True, False


def _names(entries) -> list[str]:
    names = []
    for entry in entries:
        names += [n.strip().lstrip("*") for n in entry.name.split(",") if n.strip()]
    return names


CALLABLES = sorted(_callables(), key=lambda c: c[0])


def test_the_scan_finds_the_package():
    names = {c[0] for c in CALLABLES}
    assert {"station.plant.simulate.simulate", "station.link.open_session", "station.protocol.v1.Decoder.feed",
            "station.sim.device.SimDevice"} <= names
    assert len(CALLABLES) > 200


@pytest.mark.parametrize("qualname, func, doc, skip_first, record", CALLABLES, ids=[c[0] for c in CALLABLES])
def test_parameters_are_documented(qualname, func, doc, skip_first, record):
    params = list(inspect.signature(func).parameters)[1 if skip_first else 0:]
    if not params:
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # docscrape warns on sections it does not know
        parsed = docscrape.NumpyDocString(doc or "")
    documented = _names(parsed["Parameters"]) + _names(parsed["Other Parameters"])
    if record:
        documented += _names(parsed["Attributes"])
    missing = [p for p in params if p not in documented]
    assert not missing, f"{qualname}: parameters not documented: {', '.join(missing)}"
    if not record:
        stale = [d for d in _names(parsed["Parameters"]) + _names(parsed["Other Parameters"]) if d not in params]
        assert not stale, f"{qualname}: documented but not parameters: {', '.join(stale)}"


def _own_nodes(func):
    """The nodes of ``func``'s body, not descending into nested functions, lambdas or classes."""
    stack = list(func.body)
    while stack:
        node = stack.pop()
        yield node
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            stack.extend(ast.iter_child_nodes(node))


def _public_functions(tree):
    """(qualified name, node) of each public function and method of a module: no part of its
    name starts with "_", and it is not local to another function (a closure is no API)."""
    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.ClassDef):
                yield from visit(child, f"{prefix}{child.name}.")
            elif isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = f"{prefix}{child.name}"
                if not any(part.startswith("_") for part in name.split(".")):
                    yield name, child
            else:
                yield from visit(child, prefix)
    yield from visit(tree, "")


def _returns_a_value(func) -> bool:
    return any(isinstance(n, ast.Return) and n.value is not None or isinstance(n, (ast.Yield, ast.YieldFrom))
               for n in _own_nodes(func))


def _is_property(func) -> bool:
    """A property describes its value in its summary line."""
    return any(ast.unparse(d).split(".")[-1] in ("property", "cached_property") for d in func.decorator_list)


def _value_returning(package: str):
    """``(where, docstring)`` of each public value-returning function of ``station.<package>``
    (properties aside), ``where`` as ``path:line qualified.name``."""
    root = pathlib.Path(station.__file__).parent
    for path in sorted((root / package).rglob("*.py")):
        for name, node in _public_functions(ast.parse(path.read_text(encoding="utf-8"))):
            if _returns_a_value(node) and not _is_property(node):
                yield f"{path.relative_to(root.parent)}:{node.lineno} {name}", ast.get_docstring(node) or ""


@pytest.mark.parametrize("package", ["diagnosis", "design"])
def test_value_returning_functions_document_what_they_return(package):
    """Every public function of the package that returns (or yields) a value says what in a
    numpydoc Returns (or Yields) section: its type, shape and units."""
    found = list(_value_returning(package))
    assert len(found) > 60  # the walk reaches the package
    missing = [where for where, doc in found if not re.search(r"^(Returns|Yields)\n-+$", doc, re.M)]
    assert not missing, (f"{len(missing)} of {len(found)} public functions return a value but document no "
                         f"Returns/Yields section:\n" + "\n".join(missing))


EXAMPLES = ["station.plant.simulate.simulate", "station.analysis.metrics.step_metrics", "station.runlog.reader.read_log",
            "station.diagnosis.pipeline.diagnose", "station.design.tuning.tune"]
"""The entry points whose Examples are doctested here (``run_step`` and ``plan_step``: tests/test_step.py)."""


@pytest.mark.parametrize("name", EXAMPLES)
def test_the_examples_run(name, tmp_path, monkeypatch):
    """Each entry point's Examples section runs and prints what it shows (in a scratch folder)."""
    import doctest
    import io

    module, attr = name.rsplit(".", 1)
    func = getattr(importlib.import_module(module), attr)
    monkeypatch.chdir(tmp_path)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    out = io.StringIO()
    for test in doctest.DocTestFinder().find(func, attr, globs={}):
        runner.run(test, out=out.write)
    assert runner.tries >= 4 and runner.failures == 0, out.getvalue()
