"""Frequency responses: the H1 estimator against known filters, the model's response
against a simulated sine, and the rig's swept sine against DESIGN.md's antiresonances
(≈ 2.5 Hz and 17.7 Hz)."""

import argparse
import json

import numpy as np
import pytest
import scipy.signal

from station.analysis.frequency import compare_bode, h1_estimate, model_response, notch_frequencies
from station.commands import bode
from station.plant import DiscretePlant

FS = 500.0
SWEPT = "swept_sine_kp_1_amp_50.txt"


def test_h1_recovers_a_known_filter_with_output_noise():
    rng = np.random.default_rng(1)
    b, a = scipy.signal.iirnotch(20.0, 5.0, fs=FS)  # notch at 20 Hz
    x = rng.standard_normal(200_000)
    y = scipy.signal.lfilter(b, a, x) + 0.05 * rng.standard_normal(x.size)
    est = h1_estimate(x, y, FS, nperseg=2048)
    _, H = scipy.signal.freqz(b, a, worN=est.f, fs=FS)
    band = (est.f > 1) & (np.abs(est.f - 20) > 2)
    assert np.abs(est.H[band] - H[band]).max() < 0.02
    assert est.coherence[band].min() > 0.95
    assert notch_frequencies(est.f, est.H, [18.0])[0] == pytest.approx(20.0, abs=FS / 2048)


def test_model_response_matches_a_simulated_sine():
    plant = DiscretePlant(n_elements=4)
    for f in (2.0, 9.0, 18.0):
        t = np.arange(10_000) / FS
        theta, a = plant.simulate_open_loop(np.sin(2 * np.pi * f * t))
        plant.reset()
        tail = t > 12.0  # transients gone (slowest elastic decay ~0.5 s); integrator gives an offset
        X = np.column_stack([np.ones(tail.sum()), np.sin(2 * np.pi * f * t[tail]), np.cos(2 * np.pi * f * t[tail])])
        expected = model_response(plant, [f])[:, 0]
        for y, h in ((theta, expected[0]), (a, expected[1])):
            c = np.linalg.lstsq(X, y[tail], rcond=None)[0]
            assert complex(c[1], c[2]) == pytest.approx(h, rel=1e-4)


def test_model_response_rejects_zero_frequency():
    with pytest.raises(ValueError, match="frequencies"):
        model_response(DiscretePlant(n_elements=1), [0.0, 1.0])


@pytest.fixture(scope="module")
def swept(rig_data):
    from station.runlog import read_log

    return read_log(rig_data / SWEPT).data


def test_rig_antiresonances(swept):
    cmp = compare_bode(swept["v"], swept["theta"], swept["a"], 0.002, DiscretePlant(n_elements=4))
    measured = cmp.antiresonances_measured_hz
    assert measured[0] == pytest.approx(2.5, abs=0.15)  # DESIGN.md: ≈ 2.5 Hz (2.52 Hz hub held)
    assert measured[1] == pytest.approx(17.7, abs=0.3)  # DESIGN.md: ≈ 17.7 Hz
    assert np.all(np.abs(cmp.antiresonance_error_pct[:2]) < 5.0)
    band = (cmp.theta.f > 1) & (cmp.theta.f < 15) & (np.abs(cmp.theta.f - 2.5) > 0.5)
    assert np.median(cmp.theta.coherence[band]) > 0.9
    # the model's magnitude follows the rig's within a factor of 2 over the coherent band
    ratio = np.abs(cmp.model[0][band]) / np.abs(cmp.theta.H[band])
    assert np.all((ratio > 0.5) & (ratio < 2.0))


def test_bode_command_writes_figure_and_json(rig_data, tmp_path, capsys):
    parser = argparse.ArgumentParser()
    bode.configure(parser)
    png, out = tmp_path / "b.png", tmp_path / "b.json"
    assert bode.run(parser.parse_args([str(rig_data / SWEPT), "--png", str(png), "--json", str(out)])) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rows = json.loads(out.read_text())["antiresonances"]
    assert len(rows) >= 2 and rows[0]["measured_hz"] == pytest.approx(2.5, abs=0.15)
    assert "measured Hz" in capsys.readouterr().out


@pytest.mark.parametrize("zeroed, said", [((3,), "v never changes"), ((2, 3, 4, 5), "v never changes"),
                                          ((4,), "θ never changes")])
def test_bode_refuses_a_run_nothing_drove(rig_data, tmp_path, zeroed, said):
    """A fuzzing round: the swept sine with v (or every column) zeroed gave 'measured' antiresonances
    of 1.95 and 13.8 Hz from 0/0, exit 0. θ/v needs a v that moves and a θ that answers."""
    from station.errors import StationError

    lines = (rig_data / SWEPT).read_text().splitlines()
    out = []
    for ln in lines:
        f = ln.split("\t")
        if ln and not ln.startswith(("#", "Time")) and len(f) > 5:
            for k in zeroed:
                f[k] = "0"
        out.append("\t".join(f))
    path = tmp_path / "zeroed.txt"
    path.write_text("\n".join(out) + "\n")
    parser = argparse.ArgumentParser()
    bode.configure(parser)
    with pytest.raises(StationError, match=said):
        bode.run(parser.parse_args([str(path), "--png", str(tmp_path / "b.png")]))
    assert not (tmp_path / "b.png").exists()


def test_measured_phase_is_drawn_on_the_models_branch():
    # Across a lightly damped antiresonance the phase jumps by about +180° within one bin:
    # the model by +170°, the noisy measurement by +195°, which np.unwrap takes as -165°.
    # Unwrapped each on its own they end a whole turn apart; on the model's branch the gap
    # is the true one (-20°, then +5°) and never above 180°.
    from station.analysis.frequency import phase_beside

    f = np.linspace(0.5, 40, 400)
    notch = f > 20.0
    model = np.exp(1j * np.radians(-12.0 * f + 170.0 * notch))
    measured = np.exp(1j * np.radians(-12.0 * f - 20.0 + 195.0 * notch))
    ref = np.degrees(np.unwrap(np.angle(model)))
    assert np.max(np.abs(np.degrees(np.unwrap(np.angle(measured))) - ref)) > 300  # the old drawing
    gap = phase_beside(measured, model) - ref
    assert np.all(np.abs(gap) <= 180 + 1e-9)
    np.testing.assert_allclose(gap, np.where(notch, 5.0, -20.0), atol=1e-9)
