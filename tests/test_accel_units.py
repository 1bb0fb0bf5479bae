"""The a column's unit: a claim checked against its data like θ's.

The class of defect: the audit checked θ's unit (radians, degrees) and t's (ms) but took a for
the rig's accelerometer counts on trust, and judged it with thresholds in counts (half a count
of noise at least, DESIGN.md "Log audit"). The rig's own logs with a stored in m/s² or g (a
lab script scaling the converter's counts by the sensitivity) were all called "no tip
acceleration: it reads noise where the tip moved" and their a fits were -5000 to -100000 %.
The invariant tested here: a column that steps by whole multiples of another size than one
count is converted by that size, and says so; one with no common step is judged by its own
noise, not a count's; a column of counts is left as it is, whatever its offset.

Truth: the rig's own logs (``../shared/data/rig``) rewritten as such a script would have
written them, and the rig's a as logged (the thesis's lead + accelerometer log stores counts +
0.04).
"""

from __future__ import annotations

import numpy as np
import pytest

from station.logged import LoggedRun
from station.logged.audit import ACCEL_CLAIM, accel_step, in_counts
from station.logged.sensor_evidence import sensor_evidence
from station.plant.model import load_model
from station.logged.units import ACCEL_UNIT_CLAIM, accel_unit
from station.replay import replay
from tests.test_sensor_reach import THESIS, _rewrite

A_GAIN = 1.1452654922936827
"""The rig's accelerometer sensitivity, counts per m/s² (DESIGN.md's a_gain)."""

G = 9.80665

SCALES = {"m/s²": 1.0 / A_GAIN, "g": 1.0 / (A_GAIN * G), "mV of a 3.3 V 12-bit converter": 3300.0 / 4096}


@pytest.fixture(scope="module")
def nominal():
    return load_model("tmm-fit")


def _printed(x, digits):
    return np.array([float(f"{v:.{digits}g}") for v in x])


@pytest.mark.parametrize("unit", SCALES)
@pytest.mark.parametrize("name", THESIS)
def test_a_scaled_into_another_unit_is_read_back_in_counts(rig_data, tmp_path, unit, name):
    """Rewritten with a in another unit (printed to 7 digits), the log's a is found to step by
    one count's size in that unit, converted back to the rig's very counts, and replayed as
    the rig's own log is (the same a fit, no sensor fault decided, no silence)."""
    scale = SCALES[unit]
    src = rig_data / name
    path = _rewrite(src, tmp_path / name, lambda t, a: _printed(a * scale, 7))
    clean, run = LoggedRun.from_path(src), LoggedRun.from_path(path)
    assert np.allclose(run.data["a"], clean.data["a"], rtol=0, atol=1e-9)
    (claim,) = [c for c in run.audit.claims if c.header == ACCEL_UNIT_CLAIM]
    assert claim.verdict == "contradicted" and claim.data.startswith("a in steps of")
    assert run.audit.lines()[0].startswith(f"header: {ACCEL_UNIT_CLAIM}; data: a in steps of")
    assert not any(c.header == ACCEL_CLAIM for c in run.audit.claims)
    assert run.sensors.effects == clean.sensors.effects
    assert replay(path).fit_pct == pytest.approx(replay(src).fit_pct, abs=0.05)


@pytest.mark.parametrize("name", THESIS)
def test_a_float_with_no_count_is_judged_by_its_own_noise_and_its_scale_decided(rig_data, tmp_path, name, nominal):
    """a computed in floats (scaled into g with noise of its own, no common step) is not called
    a silent channel (its noise at rest, not half a count, is what it is judged against), and
    its scale is decided as the accelerometer's gain: with the sign, and against the clean
    log's own ratio over the model's a times the scale to within 25 %."""
    rng = np.random.default_rng(7)
    scale = SCALES["g"]
    path = _rewrite(rig_data / name, tmp_path / name,
                    lambda t, a: a * scale + 0.02 * scale * rng.standard_normal(a.size))
    run, clean = LoggedRun.from_path(path), LoggedRun.from_path(rig_data / name)
    (claim,) = [c for c in run.audit.claims if c.header == ACCEL_UNIT_CLAIM]
    assert claim.verdict == "unchecked"
    assert not any(c.header == ACCEL_CLAIM for c in run.audit.claims), run.audit.lines()
    clean_gain = sensor_evidence(clean, nominal).accel_ratio  # the rig's a is 1.0-1.4x the model's
    gain = run.sensors.effects["accel_gain"]
    assert 0.75 * scale * clean_gain <= gain <= 1.25 * scale * clean_gain, (gain, scale * clean_gain)


def test_a_dead_float_channel_is_still_silent(rig_data, tmp_path):
    """The other side of judging a float by its own noise: a channel that reads only its noise
    while the model's tip moves is still no tip acceleration."""
    rng = np.random.default_rng(3)
    name = THESIS[1]
    path = _rewrite(rig_data / name, tmp_path / name, lambda t, a: 0.013 + 0.001 * rng.standard_normal(a.size))
    run = LoggedRun.from_path(path)
    assert any(c.header == ACCEL_CLAIM and c.verdict == "contradicted" for c in run.audit.claims), run.audit.lines()


def test_the_rigs_own_a_is_in_counts(rig_data):
    """Every log of the rig's in ``../shared`` (the lead + accelerometer log's counts + 0.04 too)
    has its a in counts: no unit claim, nothing converted."""
    paths = sorted(rig_data.rglob("*.txt"))
    assert len(paths) >= 11
    for path in paths:
        run = LoggedRun.from_path(path)
        assert accel_unit(run.raw_log.data["a"]) is None, path.name
        assert in_counts(run.raw_log.data["a"]), path.name


@pytest.mark.parametrize("a, step", [
    (np.array([0.04, 1.04, -2.96, 0.04]), 1.0),            # counts on an offset
    (np.array([0.0, 6.0, -12.0, 0.0]), 6.0),               # whole counts of a sensor 6x the gain (in counts)
    (np.array([0.0, 0.25, 0.5, -0.75, 0.0]), 0.25),
    (np.array([3.0, 3.0, 3.0]), None),                     # never changes
    (np.array([0.1, 0.35, 0.2, 0.9]), None),               # no common step
    (np.round(np.linspace(-1.0, 1.0, 50) ** 3, 6), None),  # the printing's last digit: 2e6 steps over its range
])
def test_accel_step(a, step):
    got = accel_step(a)
    assert (got is None) if step is None else got == pytest.approx(step, rel=1e-9)


@pytest.mark.parametrize("a, counts", [
    (np.array([0.04, 1.04, -2.96, 0.04]), True),
    (np.array([0.0, 6.0, -12.0, 0.0]), True),   # a gain of 6 read in whole counts: the gain says it
    (np.array([2.0, 2.0, 2.0]), True),
    (np.array([0.0, 0.25, 0.5, -0.75]), False),
    (np.array([0.1, 0.35, 0.2, 0.9]), False),
])
def test_in_counts(a, counts):
    assert in_counts(a) is counts


def test_a_diagnosis_of_logs_with_a_in_g_is_the_rigs_own(rig_data, tmp_path):
    """The diagnosis sees the rig's counts again: the same causes and values as on the logs
    themselves (before: every run's a 'no tip acceleration', the a evidence lost)."""
    from station.diagnosis import diagnose

    scale = SCALES["g"]
    paths = [_rewrite(rig_data / name, tmp_path / name, lambda t, a: _printed(a * scale, 7)) for name in THESIS]
    scaled, clean = (diagnose([str(p) for p in ps], workers=1) for ps in (paths, [rig_data / n for n in THESIS]))
    assert scaled.causes == clean.causes and not scaled.decided_faults
    assert scaled.extended_model.effect_dict() == pytest.approx(clean.extended_model.effect_dict(), rel=1e-9)
    assert scaled.gain_pct == pytest.approx(clean.gain_pct, abs=1e-9)
