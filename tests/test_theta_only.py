"""A lab archive logged without the accelerometer (t n u v θ, no a column): the diagnosis
fits θ alone, leaves the accelerometer's faults out of its vocabulary (nothing shows them),
and says so; a run whose controller feeds a back is still refused, naming the column.

Blind: the logs are the independent generator's (tests/blind), their a column cut away by
plain text editing here, not by the station's reader."""

from __future__ import annotations

import json
import math

import pytest

from station import cli, diagnosis
from station.diagnosis.sessions.diagnose import diagnose_sessions
from station.diagnosis.sessions.logs import group_sessions
from tests.blind.cases import TOLERANCE, value_error
from tests.blind.generator import write_case

HIDDEN = {"amp_offset": -5.81, "coulomb_friction": 9.17}
"""A rig with a sliding friction and an amplifier offset (blind case amp_offset+coulomb_friction,
seed 1, rounded)."""


def _without_a(text: str) -> str:
    """The log with its a column (and any after it) cut away: its first five tab-separated
    fields on the column line and on every row."""
    return "\n".join(line if line.startswith("#") and not line.startswith("#t") else "\t".join(line.split("\t")[:5])
                     for line in text.splitlines()) + "\n"


@pytest.fixture(scope="module")
def theta_only(tmp_path_factory):
    """The P step, lead step and open-loop pulses of a blind case, saved without a; and the
    lead + accelerometer step so saved."""
    folder = tmp_path_factory.mktemp("theta_only")
    p_step, lead, lead_accel, pulses = write_case(folder / "logs", HIDDEN, 1)
    for path in (p_step, lead, lead_accel, pulses):
        path.write_text(_without_a(path.read_text()))
    assert "\ta" not in p_step.read_text().splitlines()[2]
    return [str(p_step), str(lead), str(pulses)], str(lead_accel)


@pytest.mark.slow
def test_a_theta_only_archive_is_diagnosed_from_theta(theta_only, tmp_path, capsys):
    runs, _ = theta_only
    out = tmp_path / "d.json"
    assert cli.main(["diagnose", *runs, "--json", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    j = json.loads(out.read_text())
    found = {e["name"]: e["value"] for e in j["effects"] if e["accepted"]}
    assert set(found) == set(HIDDEN), (found, j["causes"])
    for name, value in HIDDEN.items():
        assert value_error(value, found[name]) <= TOLERANCE, (name, found[name])
    assert j["unexplained"] is False, j["unexplained_evidence"]
    # nothing in these runs shows an accelerometer: its faults are not searched, nor said
    assert not [e["name"] for e in j["effects"] if e["name"].startswith("accel_")]
    assert "a fit n/a -> n/a" in printed
    assert sum("the log has no a column: its θ alone is fitted" in n for n in j["notes"]) == 3


@pytest.mark.slow
def test_a_theta_only_session_is_diagnosed_from_theta(theta_only):
    runs, _ = theta_only
    result = diagnose_sessions(group_sessions(runs), candidates=("coulomb_friction", "amp_offset", "param:drive_c",
                                                                 "accel_gain"))
    assert set(result.shared) == set(HIDDEN), result.shared
    for name, value in HIDDEN.items():
        assert value_error(value, result.shared[name]) <= TOLERANCE, (name, result.shared[name])
    assert sum("the log has no a column" in n for n in result.notes) == 3


def test_a_run_whose_controller_feeds_a_back_is_refused_without_a(theta_only, capsys):
    runs, lead_accel = theta_only
    assert cli.main(["diagnose", runs[0], lead_accel, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "no 'a' column: a diagnosis (the run simulated on a model and fitted) needs u, theta, v, a" in err, err


@pytest.mark.slow
def test_a_run_without_a_beside_runs_whose_bias_is_decided(tmp_path):
    """An accelerometer bias decided over the runs with a (held in the model, each run's a kept
    as logged) leaves the run without a column at zeros, not at the reader's NaN."""
    hidden = {"accel_offset": -2.33}  # blind case accel_offset seed 2: a session decides it
    paths = write_case(tmp_path / "logs", hidden, 2)
    paths[0].write_text(_without_a(paths[0].read_text()))
    result = diagnosis.diagnose([str(p) for p in paths])
    assert result.sensor_faults.effects == pytest.approx(hidden, rel=TOLERANCE), result.sensor_faults.effects
    assert result.accepted == [] and not result.unexplained.flag, result.unexplained.evidence
    assert all(math.isfinite(r.fit_nominal["theta"]) for r in result.runs)
    json.dumps(result.to_json(), allow_nan=False)  # no NaN from the missing column anywhere
