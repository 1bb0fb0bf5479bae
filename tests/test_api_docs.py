"""The docs site's API reference covers what a notebook calls, and reads the docstrings right.

The reference is the pages under docs/api/ (``::: station.module`` blocks, rendered by
mkdocstrings from the docstrings; ``mkdocs build --strict`` in CI fails on one it cannot
find). Here, without building: every block names a module of the package, every page is in
mkdocs.yml's navigation, the entry points of the package (the README's, the docs' Python
calls) are each in a documented module, and the griffe extension turns the docstrings'
Sphinx roles into links resolved where the docstring is.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
API = REPO / "docs" / "api"

ENTRY_POINTS = [  # (module, name): what a script or a notebook calls
    ("station.rig", "DT"), ("station.rig", "CLAMP"),
    ("station.experiment", "run_step"), ("station.experiment", "StepReport"),
    ("station.plan", "plan_step"), ("station.plan", "StepPlan"),
    ("station.plant.simulate", "simulate"), ("station.plant.model", "Model"), ("station.plant.model", "load_model"),
    ("station.analysis.metrics", "step_metrics"), ("station.analysis.metrics", "step_info"),
    ("station.runlog.reader", "read_log"), ("station.runlog.log", "RunLog"), ("station.runlog.writer", "RunLogWriter"),
    ("station.control.designs", "make_controller"), ("station.control.designs", "read_compensator_file"),
    ("station.control.compensator", "Compensator"), ("station.control.contract", "Controller"),
    ("station.control.reference", "step_reference"),
    ("station.logged.run", "LoggedRun"),
    ("station.replay", "replay"), ("station.compare", "compare_run"), ("station.survey", "survey"),
    ("station.diagnosis.pipeline", "diagnose"), ("station.diagnosis.answer.result", "Diagnosis"),
    ("station.diagnosis.identify.loop", "identify"), ("station.diagnosis.sessions.diagnose", "diagnose_sessions"),
    ("station.design.tuning", "tune"), ("station.design.tuning", "TuneResult"), ("station.design.verify", "verify"),
]


def documented() -> dict[str, Path]:
    """Each ``::: identifier`` of the API pages -> its page."""
    out = {}
    for page in sorted(API.glob("*.md")):
        for ident in re.findall(r"^:::\s*(\S+)", page.read_text(), flags=re.M):
            out[ident] = page
    return out


def test_every_block_names_a_module_of_the_package():
    blocks = documented()
    assert len(blocks) >= 20
    for ident, page in blocks.items():
        assert ident.startswith("station"), f"{page.name}: {ident}"
        importlib.import_module(ident)  # a module, whose public members the block renders


def test_every_api_page_is_in_the_navigation():
    nav = (REPO / "mkdocs.yml").read_text()
    missing = [p.name for p in API.glob("*.md") if f"api/{p.name}" not in nav]
    assert not missing, f"API pages not in mkdocs.yml's nav: {missing}"


@pytest.mark.parametrize("module, name", ENTRY_POINTS)
def test_the_reference_covers_the_entry_point(module, name):
    assert module in documented(), f"{module} (for {name}) is in no page under docs/api/"
    obj = getattr(importlib.import_module(module), name)
    doc = getattr(obj, "__doc__", None) if not isinstance(obj, (int, float)) else "a fact"
    assert doc, f"{module}.{name} has no docstring for the reference"


@pytest.fixture(scope="module")
def roles():
    import griffe  # lazy: the tests' extras install it (griffelib), the package does not need it

    extensions = griffe.load_extensions(str(REPO / "scripts" / "griffe_roles.py") + ":SphinxRoles")
    return griffe.load("station.experiment", extensions=extensions, search_paths=[str(REPO)])


def test_roles_become_links_resolved_where_the_docstring_is(roles):
    run_step = roles["run_step"].docstring.value
    assert ":class:" not in run_step and ":func:" not in run_step
    # ~ shows the last part; a full path stays as it is
    assert '<autoref identifier="station.plan.StepPlan" optional><code>StepPlan</code></autoref>' in run_step
    assert '<autoref identifier="station.plan.plan_step" optional><code>station.plan.plan_step</code></autoref>' \
        in run_step
    # a relative name: the module's own object, and a name it imports
    module = roles.docstring.value
    assert '<autoref identifier="station.experiment.run_step" optional><code>run_step</code></autoref>' in module
    assert "(in a notebook):\n" in module  # reST's "::" before a literal block


def test_a_relative_name_resolves_through_the_class_and_the_imports(roles):
    import sys

    sys.path.insert(0, str(REPO / "scripts"))
    try:
        from griffe_roles import resolve
    finally:
        sys.path.pop(0)
    report = roles["StepReport"]
    assert resolve(report, "to_pandas") == "station.experiment.StepReport.to_pandas"
    assert resolve(roles, "StepPlan") == "station.plan.StepPlan"          # imported from station.plan
    assert resolve(roles, "read_log") == "station.runlog.read_log"         # imported from station.runlog
    assert resolve(roles, "nothing_by_that_name") == "nothing_by_that_name"
