"""No two texts of a figure the station draws sit on each other: the y-labels of stacked panels
(issue 24: bode's '|a/v| (dB, counts/count)' ran into the phase panel's 'unwrapped on the
model's'), and a panel's title or axis label over another panel's.

Every figure a command writes is caught as it is saved (``Figure.savefig``) and its axes'
labels measured with the renderer that draws them.
"""

from __future__ import annotations

import itertools
import shutil

import pytest
from matplotlib.figure import Figure

from station.cli import main
from tests.output_cases import make_inputs


def _boxes(fig):
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        for label in (ax.yaxis.label, ax.xaxis.label, ax.title):
            if label.get_text() and label.get_visible():
                yield ax, label.get_text(), label.get_window_extent(renderer)


def overlaps(fig) -> list[tuple[str, str]]:
    """Pairs of labels of different axes whose boxes intersect."""
    found = []
    for (a1, t1, b1), (a2, t2, b2) in itertools.combinations(list(_boxes(fig)), 2):
        if a1 is not a2 and b1.overlaps(b2):
            found.append((t1, t2))
    return found


@pytest.fixture
def saved(monkeypatch):
    figures = []
    real = Figure.savefig

    def catch(self, *args, **kwargs):
        figures.append(self)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", catch)
    return figures


COMMANDS = {
    "bode": ["bode", "{sweep}", "--nperseg", "1024", "--out-dir", "out"],
    "compare": ["compare", "{step}", "--out-dir", "out"],
    "plot": ["plot", "{step}", "{step2}", "--out-dir", "out"],
    "step": ["step", "--duration", "0.2", "--quiet", "--out-dir", "out"],
    "diagnose --report": ["diagnose", "{step}", "{step2}", "--report", "out", "--quiet"],
    "survey --diagnose --report": ["survey", "--diagnose", "{in}", "--model", "{model}", "--report", "out"],
    "tune --report": ["tune", "--controller", "lead", "--samples", "0", "--shaper", "none", "--jobs", "1", "--model",
                      "{model}", "--quiet", "--report", "out", "--out", "out.toml"],
    "identify --report": ["identify", "--budget", "0", "--model", "{model}", "--out-dir", "exp", "--quiet", "--report",
                          "out"],
}


@pytest.mark.parametrize("name", COMMANDS)
def test_no_label_of_a_figure_runs_into_another_panels(tmp_path, monkeypatch, saved, capsys, name):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("station.diagnosis.search.workbench.CANDIDATES", ("coulomb_friction",))
    inputs = make_inputs(tmp_path)
    argv = [a.format(**{k: str(v) for k, v in inputs.items()}) for a in COMMANDS[name]]
    assert main(argv) == 0, capsys.readouterr().err
    assert saved, "the command drew a figure"
    for fig in saved:
        assert overlaps(fig) == [], (name, fig.texts[0].get_text() if fig.texts else "")
    shutil.rmtree(tmp_path / "out", ignore_errors=True)
