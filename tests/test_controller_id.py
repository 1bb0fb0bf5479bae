"""Controller identification as lab software ran it: recursions on the stored integer
(truncated or rounded), both alignments, the clamp, P with any gain, and the continuous
design behind a law (Tustin, ZOH, backward Euler) recognised with its round numbers.

The truth comes from code that is not the station's: the blind generator's lab recursion
(tests/blind/audit.py ``LabController``) and scipy's discretizations."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.signal import cont2discrete

from station.analysis.continuous_design import METHODS, discretize, nicest_between, to_continuous
from station.analysis.controller_id import TOLERANCE, infer_controller, with_recursion
from station.control import make_controller
from station.control.compensator import Compensator
from station.control.tf import DiscreteTF
from tests.blind.audit import LabController


def _scipy_law(num_s, den_s, dt, method):
    """The z-law by scipy (ascending z^-1, den[0] = 1)."""
    how = {"Tustin": ("bilinear", None), "ZOH": ("zoh", None), "backward Euler": ("gbt", 1.0),
           "forward Euler": ("gbt", 0.0)}[method]
    num, den, _ = cont2discrete((num_s, den_s), dt, method=how[0], alpha=how[1])
    num = np.atleast_1d(np.squeeze(num))
    num = np.concatenate([np.zeros(len(den) - num.size), num])
    return num / den[0], np.asarray(den) / den[0]


def _closed_loop(step, d, n=2000, seed=0):
    """u, theta, v of a law closed around a crude integrator plant (rounded θ); the
    reference a random staircase."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.integers(-120, 120, n // 100 + 1).astype(float), 100)[:n]
    theta, v = np.zeros(n), np.zeros(n)
    for k in range(n):
        if k >= d:
            v[k] = step(u[k] - theta[k - d])
        if k + 1 < n:
            theta[k + 1] = np.round(theta[k] + 0.02 * v[k] - 0.001 * theta[k])
    return u, theta, v


@pytest.mark.parametrize("method", ["Tustin", "ZOH", "backward Euler"])
@pytest.mark.parametrize("recursion", ["trunc", "round"])
@pytest.mark.parametrize("d", [0, 1])
def test_integer_recursion_reproduced_exactly_and_its_design_recognised(method, recursion, d):
    num, den = _scipy_law([3.0, 39.0], [1.0, 20.0], 0.002, method)  # 3(s+13)/(s+20)
    lab = LabController(num, den, 200.0, recursion)
    u, theta, v = _closed_loop(lab.step, d)
    assert np.all(v == np.round(v)) and np.max(np.abs(v)) == 200.0  # whole counts, clamped somewhere
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.alignment == d and hit.max_abs_dv == 0.0
    assert hit.controller.recursion == recursion and hit.recursion == recursion
    assert hit.design is not None and hit.design.method == method and hit.design.text == "3(s+13)/(s+20)"
    np.testing.assert_allclose(hit.design.num_s, [3.0, 39.0], rtol=1e-12)
    np.testing.assert_allclose(hit.design.den_s, [1.0, 20.0], rtol=1e-12)
    assert "truncated" in hit.law if recursion == "trunc" else "rounded" in hit.law


@pytest.mark.parametrize("method", ["Tustin", "ZOH"])
@pytest.mark.parametrize("stored", ["trunc", "round"])
@pytest.mark.parametrize("d", [0, 1])
def test_a_float_recursion_logged_as_the_whole_counts_it_sent_is_found(method, stored, d):
    """Lab software that recurses on the float and logs (and sends) the whole count: its float
    history is not in the log; the design is found from its poles and zeros (the law's own
    float run fitted to the logged counts) and its gain from the rows' exact bounds."""
    num, den = _scipy_law([3.0, 39.0], [1.0, 20.0], 0.002, method)  # 3(s+13)/(s+20)
    lab = LabController(num, den, 200.0, f"float-{stored}")
    u, theta, v = _closed_loop(lab.step, d)
    assert np.all(v == np.round(v)) and np.max(np.abs(v)) == 200.0
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.max_abs_dv == 0.0 and d in hit.alignments
    assert hit.recursion == f"float-{stored}" and hit.design.method == method
    assert hit.design.text == "3(s+13)/(s+20)"
    assert f"its recursion on the float, the command sent as its {'truncated' if stored == 'trunc' else 'rounded'} " \
           "integer" in hit.law


@pytest.mark.parametrize("seed", range(6))
def test_the_sent_gain_interval_holds_exactly_the_gains_that_reproduce(seed):
    """sent_gain_interval against the generator's lab recursion run at gains on both sides of
    each end: inside (by a part in 10^6 of the width) every logged v is given, outside (by a
    tenth of the width) some row differs; and the hidden gain is inside."""
    from station.analysis.sent_law import sent_gain_interval

    rng = np.random.default_rng(seed)
    k, z = float(rng.choice([1.0, 1.5, 2.0, 3.0])), float(rng.integers(5, 30))
    p = z + float(rng.integers(5, 60))
    stored, d = str(rng.choice(["trunc", "round"])), int(rng.integers(0, 2))
    num, den = _scipy_law([k, k * z], [1.0, p], 0.002, "Tustin")
    u, theta, v = _closed_loop(LabController(num, den, 200.0, f"float-{stored}").step, d, seed=seed)
    e = np.zeros(u.size)
    e[d:] = u[d:] - theta[:u.size - d]
    lo, hi = sent_gain_interval(e, v, d, 200.0, stored, (num / k)[None], den[None], np.array([k]))
    lo, hi = float(lo[0]), float(hi[0])
    assert lo <= k <= hi, (lo, k, hi)

    def gives(gain):
        lab = LabController(num / k * gain, den, 200.0, f"float-{stored}")
        w = np.zeros(u.size)
        for i in range(d, u.size):
            w[i] = lab.step(e[i])
        return np.array_equal(w, v)

    width = hi - lo
    assert gives(lo + 1e-6 * width) and gives(hi - 1e-6 * width)
    assert not gives(lo - 0.1 * width) and not gives(hi + 0.1 * width)


@pytest.mark.parametrize("kp, recursion, d", [(0.5, "trunc", 1), (1.2, "round", 0), (2.5, "trunc", 0), (0.37, "none", 1)])
def test_p_with_any_gain(kp, recursion, d):
    lab = LabController([kp], [1.0], 200.0, recursion)
    u, theta, v = _closed_loop(lab.step, d)
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.controller.spec["kp"] == kp and hit.max_abs_dv == 0.0
    assert hit.alignment == d or d in hit.alignments


def test_the_logs_own_clamp():
    num, den = _scipy_law([2.5, 42.5], [1.0, 63.0], 0.002, "Tustin")
    lab = LabController(num, den, 150.0, "none")
    u, theta, v = _closed_loop(lab.step, 1)
    assert np.max(np.abs(v)) == 150.0
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.controller.limit == 150.0 and hit.max_abs_dv <= TOLERANCE
    assert hit.design.text == "2.5(s+17)/(s+63)" and "clamp ±150" in hit.law


@pytest.mark.parametrize("recursion", ["none", "trunc"])
@pytest.mark.parametrize("design", [((2.5, 75.0), (1.0, 90.0), "2.5(s+30)/(s+90)"),
                                    ((1.25, 12.5), (1.0, 40.0), "1.25(s+10)/(s+40)"),
                                    ((7.5, 150.0), (1.0, 50.0), "7.5(s+20)/(s+50)")])
def test_a_gain_of_more_digits_than_its_roots_is_recognised(design, recursion):
    """The roots round at fewer digits than the gain: the roots found at their level must
    still be given the gain's digits at the next (lie:a_zero seeds 7 and 8 named none)."""
    num, den = _scipy_law(design[0], design[1], 0.002, "Tustin")
    u, theta, v = _closed_loop(LabController(num, den, 200.0, recursion).step, 1)
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.design is not None and hit.design.text == design[2]
    np.testing.assert_allclose(hit.design.num_s, design[0], rtol=1e-12)


@pytest.mark.parametrize("seed", range(8))
def test_any_round_lead_is_recognised_whatever_its_digits(seed):
    """A lead K(s+z)/(s+p) of 1-3 digit gain and 1-2 digit roots, float recursion: named as typed."""
    rng = np.random.default_rng(seed)
    k = float(f"{rng.uniform(1, 9):.{int(rng.integers(0, 3))}f}")
    z = float(f"{rng.uniform(2, 40):.{int(rng.integers(1, 3))}g}")
    p = float(f"{rng.uniform(1.5, 5) * z:.{int(rng.integers(1, 3))}g}")
    num, den = _scipy_law([k, k * z], [1.0, p], 0.002, "Tustin")
    u, theta, v = _closed_loop(LabController(num, den, 200.0, "none").step, 1, seed=seed)
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.design is not None
    np.testing.assert_allclose(hit.design.num_s, [k, k * z], rtol=1e-9)
    np.testing.assert_allclose(hit.design.den_s, [1.0, p], rtol=1e-9)


def test_thesis_lead_recognised_in_hz():
    lead = make_controller("lead")
    u, theta, v = _closed_loop(lambda e: lead.step(e, 0.0, 0.0)[0], 1)
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.design is not None and hit.design.text == "20(s+2π·5)/(s+2π·20)"
    np.testing.assert_allclose(hit.controller.gth.num, lead.gth.num, rtol=1e-12)


def test_compensator_recursion_is_the_lab_recursion():
    num, den = _scipy_law([3.0, 39.0], [1.0, 20.0], 0.002, "Tustin")
    rng = np.random.default_rng(1)
    errors = rng.normal(0, 60, 3000)
    for recursion in ("trunc", "round"):
        lab = LabController(num, den, 200.0, recursion)
        comp = Compensator(DiscreteTF(num, den), None, limit=200.0, recursion=recursion)
        ours = [comp.step(e, 0.0, 0.0)[0] for e in errors]
        assert ours == [lab.step(e) for e in errors]
        again = with_recursion(Compensator(DiscreteTF(num, den), None, limit=200.0), recursion)
        assert [again.step(e, 0.0, 0.0)[0] for e in errors] == ours
    with pytest.raises(ValueError, match="recursion"):
        Compensator(DiscreteTF(num, den), recursion="floor")


def test_a_law_nobody_typed_is_reproduced_without_a_design():
    num, den = [2.41234567, -2.31234567], [1.0, -0.9213456]
    lab = LabController(num, den, 200.0, "none")
    u, theta, v = _closed_loop(lab.step, 1)
    hit = infer_controller(u, theta, v)
    assert hit is not None and hit.design is None and hit.max_abs_dv <= TOLERANCE
    np.testing.assert_allclose(hit.controller.gth.num, num, rtol=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_discretize_is_scipys_and_to_continuous_inverts_it(method):
    rng = np.random.default_rng(7)
    for _ in range(20):
        k, z, p = rng.uniform(0.5, 5), rng.uniform(1, 80), rng.uniform(1, 300)
        num_s, den_s = [k, k * z], [1.0, p]
        nz, dz = discretize(num_s, den_s, 0.002, method)
        snz, sdz = _scipy_law(num_s, den_s, 0.002, method)
        np.testing.assert_allclose(nz, snz, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(dz, sdz, rtol=1e-9, atol=1e-12)
        back = to_continuous(nz, dz, 0.002, method)
        np.testing.assert_allclose(back[0], num_s, rtol=1e-6)
        np.testing.assert_allclose(back[1], den_s, rtol=1e-6)


@pytest.mark.parametrize("b0", [0.0, 1e-17, -3e-16])
def test_a_law_with_b0_near_0_is_mapped_back_without_a_scipy_warning(b0):
    """A fitted law's b_0 near 0 (the ZOH form of a strictly proper design): scipy's tf2ss
    strips it and warns "Badly conditioned filter coefficients", which reached a user of
    ``LoggedRun`` (a P log with one v a count off, whose search recognises designs). The
    design is still the one ZOH sampled."""
    nz, dz = _scipy_law([10.0], [1.0, 20.0], 0.002, "ZOH")
    nz = np.array([b0, *np.atleast_1d(nz)[-1:]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = to_continuous(nz, dz, 0.002, "ZOH")
    np.testing.assert_allclose(back[0][-1], 10.0, rtol=1e-6)
    np.testing.assert_allclose(back[1], [1.0, 20.0], rtol=1e-6)


@pytest.mark.parametrize("lo, hi, value, digits", [(2.97, 3.02, 3.0, 1), (12.91, 13.04, 13.0, 2), (-0.52, -0.48, -0.5, 1),
                                                    (0.999999, 1.000001, 1.0, 1), (31.41, 31.42, 31.42, 4)])
def test_nicest_between(lo, hi, value, digits):
    assert nicest_between(lo, hi) == (value, digits)
    assert nicest_between(hi, lo) is None and nicest_between(math.pi, math.pi + 1e-12) is None
    assert abs(nicest_between(-1.0, 1.0)[0]) == 1.0  # never a gain of 0


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("recursion", ["trunc", "round"])
def test_a_hub_held_still_leaves_the_alignment_to_no_law(seed, recursion):
    """θ 0 on every row (friction held the hub): u[k] − θ[k] and u[k] − θ[k−1] are one error, so
    the law the lab ran reproduces the log at both alignments, and both are said, whichever way
    the law was accepted (exactly, or with rows on a quantization boundary)."""
    rng = np.random.default_rng(seed)
    k, p = float(rng.choice([1.0, 1.5, 2.0, 3.0])), float(rng.integers(30, 70))
    num, den = _scipy_law([k, k * float(rng.integers(4, 25))], [1.0, p], 0.002, "Tustin")
    lab = LabController(num, den, 200.0, recursion)
    t = np.arange(2000) * 0.002
    u = np.round(rng.uniform(20.0, 50.0) * np.sin(2 * np.pi * 5.0 * t))
    v = np.array([lab.step(x) for x in u])
    hit = infer_controller(u, np.zeros_like(u), v)
    assert hit is not None and hit.max_abs_dv == 0.0
    assert set(hit.alignments) == {0, 1}


@pytest.mark.parametrize("seed", [0, 7, 9])
def test_the_blind_still_hub_under_its_true_header_is_confirmed_at_both_alignments(tmp_path, seed):
    """The blind generator's `pair+coulomb_friction` logs where friction held the hub at 0 the
    whole run (its θ written negated is θ itself): the header's law confirmed, the swap said, the
    alignment left to both, and no sign said for a column of zeros."""
    from station.logged import LoggedRun
    from tests.blind.audit import write_audit_case

    path, hidden = write_audit_case(tmp_path, "pair+coulomb_friction", seed)
    run = LoggedRun.from_path(path)
    columns = {c.data for c in run.audit.claims if c.claim == "columns" and c.verdict == "contradicted"}
    assert run.source == "header" and run.reproduced and set(run.identified.alignments) == {0, 1}
    assert columns == {"θ and a swapped"} and not hidden.negate
    assert [c.data for c in run.audit.claims if c.claim == "alignment"] == ["alignment 0 and 1 alike"]
