"""What ``station diagnose`` and ``station identify`` print does not contradict itself: every
column of the candidates table says which fit it belongs to, and the final verdict, the table and
the JSON read one record (issue 24)."""

from __future__ import annotations

import math

import pytest

from station.commands.diagnose import CANDIDATE_COLUMNS, candidate_rows, format_diagnosis
from station.diagnosis.answer.result import Diagnosis, EffectResult
from station.diagnosis.honesty.doubt import Interval
from station.diagnosis.honesty.unexplained import Unexplained
from station.plant.model import as_model


def _effect(name, value, unit, gain, cost_gain, accepted, alone, interval=None):
    return EffectResult(name, value, unit, gain, cost_gain, accepted, f"{name} evidence", [alone, alone], alone,
                        interval, False)


def built_diagnosis(unexplained_flag: bool = False) -> Diagnosis:
    """A diagnosis whose accepted effects sit far from where they were fitted alone, one of them
    with a negative gain alone (the issue's `amp_offset -3.008 ... -144.2% -484.2% yes`)."""
    nominal = as_model(None)
    effects = [
        _effect("coulomb_friction", 4.97, "DAC counts", 30.0, 40.0, True, 8.973, Interval(4.5, 5.4, False, False)),
        _effect("amp_offset", -3.008, "DAC counts", -144.2, -484.2, True, 0.731, Interval(-3.1, -2.9, False, False)),
        _effect("deadzone", 2.5, "DAC counts", 12.0, 9.0, False, 2.5),
    ]
    ext = nominal.with_effects({"coulomb_friction": 4.97, "amp_offset": -3.008}, name="tmm-fit + 2")
    u = Unexplained(unexplained_flag, "4 of 5 runs keep structure" if unexplained_flag else "", [], [], 0)
    return Diagnosis("coulomb_friction", ["coulomb_friction", "amp_offset"], {"theta": 80.0, "accel": 50.0},
                     {"theta": 90.0, "accel": 60.0}, 35.0, effects, ext, nominal, [], "leave-one-run-out",
                     simulations=100, elapsed_s=1.0, unexplained=u)


def test_the_table_labels_the_alone_and_the_extended_columns_and_fills_each_from_its_own_fit():
    diag = built_diagnosis()
    header, *rows = candidate_rows(diag)
    for col in ("value (alone)", "θ gain (alone)", "cost gain (alone)", "value (extended)", "95 % interval (extended)"):
        assert col in header
    by_name = {r.split()[0]: r for r in rows}
    for e in diag.effects:
        r = by_name[e.name]
        words = r.split()
        # value alone is the second cell, the extended value follows the two gains
        assert float(words[1]) == pytest.approx(e.value_alone, rel=1e-3)
        if e.accepted:
            ext = float(words[words.index("%", words.index("%") + 1) + 1])
            assert ext == pytest.approx(e.value, rel=1e-3)
            assert f"{e.interval.lo:.4g} .. {e.interval.hi:.4g}" in r and r.endswith("yes")
        else:
            assert r.endswith("no")
    assert "-3.008" in by_name["amp_offset"] and "0.731" in by_name["amp_offset"]
    # the printed diagnosis uses these rows (diagnose and identify both print format_diagnosis)
    printed = format_diagnosis(diag)
    for line in candidate_rows(diag):
        assert line in printed
