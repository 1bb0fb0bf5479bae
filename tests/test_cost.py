"""The diagnosis's cost against hand-computed values: the maximum-likelihood cost with an
unknown error variance per run and signal, at least its noise level (above the noise floor
the geometric mean of the runs' normalised costs, below it least squares), and the
noise-weighted mean it replaced as the fits' cost (station/diagnosis/runs/cost.py)."""

import math

import numpy as np
import pytest

from station.diagnosis.runs.cases import RunCase
from station.diagnosis.runs.cost import Evaluator

N = 400
T = np.arange(N) / N
SINE = np.sin(2 * np.pi * 4 * T)  # whole periods: mean square 1/2, orthogonal to a constant


class _Line:
    """A stand-in model: one effect "x" (default 0), as ``with_effects`` carries it."""

    def __init__(self, x=0.0):
        self.x = x

    def with_effects(self, effects):
        return _Line(effects.get("x", self.x))


def _case(name, scale, target, sigma_theta=1.0, sigma_a=math.inf):
    c = RunCase(name, None, None, None, True, np.zeros(N), np.zeros(N), sigma_theta, sigma_a)
    c.scale, c.target = scale, target
    return c


def _simulate(case, model):
    # θ error (x − target) + 2·sin, scaled: SSR/N = scale² ((x − target)² + 2); a error scale·1
    theta = case.scale * ((model.x - case.target) + 2.0 * SINE)
    return theta, np.full(N, case.scale)


def _argmin(ev, runs):
    xs = np.linspace(0.0, 4.0, 401)
    return float(xs[int(np.argmin([ev.cost({"x": float(x)}, runs) for x in xs]))])


def test_likelihood_cost_is_the_geometric_mean_of_the_runs_normalised_costs():
    ev = Evaluator([_case("a", 1.0, 1.0, sigma_theta=0.5), _case("b", 3.0, 3.0, sigma_a=2.0)], _Line(), _simulate,
                   likelihood=True)
    x = 2.0
    j = [(1 + 2) / 0.25, 9 * (1 + 2) / 1.0, 9 / 4.0]  # run a θ; run b θ and a
    assert ev.cost({"x": x}, [0, 1]) == pytest.approx((j[0] * j[1] * j[2]) ** (1 / 3))
    arithmetic = Evaluator(ev.cases, _Line(), _simulate)  # the default
    # a's term with an infinite σ is 0 but counted: Σ‖e‖²/σ² / Σ 2N
    assert arithmetic.cost({"x": x}, [0, 1]) == pytest.approx(sum(j) / 4)


def test_likelihood_fit_does_not_follow_the_run_the_model_misses_most():
    """Scaling all of one run's errors by 100 does not move the maximum-likelihood fit (each
    run counts by its samples); the noise-weighted sum then fits that run alone."""
    even = [_case("a", 1.0, 1.0), _case("b", 1.0, 3.0)]
    lopsided = [_case("a", 100.0, 1.0), _case("b", 1.0, 3.0)]
    assert _argmin(Evaluator(even, _Line(), _simulate, likelihood=True), [0, 1]) == pytest.approx(2.0, abs=0.011)
    assert _argmin(Evaluator(lopsided, _Line(), _simulate, likelihood=True), [0, 1]) == pytest.approx(2.0, abs=0.011)
    assert _argmin(Evaluator(even, _Line(), _simulate), [0, 1]) == pytest.approx(2.0, abs=0.011)
    assert _argmin(Evaluator(lopsided, _Line(), _simulate), [0, 1]) == pytest.approx(1.0, abs=0.011)


def test_likelihood_cost_gives_no_reward_for_fitting_a_run_below_its_noise():
    """A run fitted exactly costs what least squares says (0), not ln 0: the profile
    likelihood with the error variance at least σ² is N·J below the floor, N·(ln J + 1) above."""
    ev = Evaluator([_case("exact", 0.0, 1.0), _case("b", 1.0, 3.0)], _Line(), _simulate, likelihood=True)
    j_b = (1.0 - 3.0) ** 2 + 2.0  # x = 1
    assert ev.cost({"x": 1.0}, [0, 1]) == pytest.approx(math.exp((0.0 + math.log(j_b) + 1.0) / 2 - 1.0))
    half = Evaluator([_case("a", math.sqrt(0.5 / 2.0), 1.0)], _Line(), _simulate, likelihood=True)  # J = 0.5 at x = 1
    assert half.cost({"x": 1.0}, [0]) == pytest.approx(math.exp(0.5 - 1.0))


def test_likelihood_cost_is_infinite_when_a_run_diverges():
    def diverging(case, model):
        theta, a = _simulate(case, model)
        return (np.full(N, np.inf) if case.target == 3.0 else theta), a

    ev = Evaluator([_case("a", 1.0, 1.0), _case("b", 1.0, 3.0)], _Line(), diverging, likelihood=True)
    assert ev.cost({"x": 1.0}, [0]) == pytest.approx(2.0)
    assert ev.cost({"x": 1.0}, [0, 1]) == math.inf


def test_costed_switches_the_cost_inside_the_block_only():
    ev = Evaluator([_case("a", 1.0, 1.0, sigma_theta=0.5), _case("b", 3.0, 3.0, sigma_a=2.0)], _Line(), _simulate)
    least_squares = ev.cost({"x": 1.0}, [0, 1])
    likelihood = Evaluator(ev.cases, _Line(), _simulate, likelihood=True).cost({"x": 1.0}, [0, 1])
    assert likelihood != pytest.approx(least_squares)
    with ev.costed(likelihood=True):
        assert ev.cost({"x": 1.0}, [0, 1]) == pytest.approx(likelihood)
    assert ev.cost({"x": 1.0}, [0, 1]) == pytest.approx(least_squares)
    with pytest.raises(RuntimeError), ev.costed(likelihood=True):
        raise RuntimeError("a fit that fails")
    assert not ev.likelihood  # restored on the way out of a failure too


def test_each_set_of_effects_is_simulated_on_its_own_model_to_the_last_bit():
    """The evaluator keeps one model per set of effects (its linear part is then built once
    for all runs), keyed by the exact values: effects 1e-12 apart get models 1e-12 apart
    (the errors' cache may round its key; the model simulated may not)."""
    seen = []
    ev = Evaluator([_case("a", 1.0, 0.0)], _Line(), simulate=lambda c, m: (seen.append(m), _simulate(c, m))[1])
    one = ev.model_with({"x": 1.0})
    assert ev.model_with({"x": 1.0}) is one
    near = ev.model_with({"x": 1.0 + 1e-12})
    assert near is not one and near.x == 1.0 + 1e-12
    ev.sse({"x": 2.0}, 0)
    assert seen[-1].x == 2.0


def test_a_models_remembered_linear_part_is_its_own_and_not_pickled():
    """Model remembers its parameter set and modal form (the fits' many runs of one model);
    a copy with other effects has its own, and a pickled model carries none of it."""
    import pickle

    from station.plant.model import load_model

    rig = load_model("rig")
    form = rig.linear_form()
    assert rig.linear_form() is form
    other = rig.with_effects({"param:drive_c": 2.0})
    assert other.linear_params().drive_c == pytest.approx(2.0 * rig.params.drive_c)
    assert not np.array_equal(other.linear_form().lam, form.lam)
    clone = pickle.loads(pickle.dumps(rig))
    assert clone == rig and clone._memo == {}
    assert np.array_equal(clone.linear_form().lam, form.lam)


class _Gained(_Line):
    """A stand-in model holding an accelerometer gain of -0.8 (a reversed accelerometer)."""

    def effect_dict(self):
        return {"accel_gain": -0.8}

    def with_effects(self, effects):
        return _Gained(effects.get("x", self.x))


def _shape(case, model):
    # a: -0.8 times a unit sine; θ: the effect x itself
    return np.full(N, model.x), -0.8 * SINE


class _Ga:
    ga = object()  # a controller that feeds a back


def test_a_free_accelerometer_scale_judges_a_by_its_shape_and_refits_the_gain():
    true_gain = -1.3  # the runs' a: 1.3 / 0.8 times what the model with its -0.8 gives
    cases = [_case(n, 1.0, 0.0, sigma_a=0.5) for n in "ab"] + [_case("ga", 1.0, 0.0, sigma_a=0.5)]
    for c in cases:
        c.a = true_gain * SINE
    cases[2].controller = _Ga()
    free = Evaluator(cases, _Gained(), _shape, accel_scale=(0.3 / 0.8, 3.0 / 0.8))
    held = Evaluator(cases, _Gained(), _shape)
    err = float(np.sum(((true_gain + 0.8) * SINE) ** 2))
    assert free.sse({}, 0) == pytest.approx((0.0, 0.0), abs=1e-18)
    assert held.sse({}, 0) == pytest.approx((0.0, err))
    assert free.sse({}, 2) == held.sse({}, 2)  # a fed back: judged as simulated
    assert free.fit_accel_gain({}, [0, 1, 2]) == pytest.approx(true_gain)
    assert held.fit_accel_gain({}, [0, 1]) == -0.8  # no free scale: the model's own
    tight = Evaluator(cases, _Gained(), _shape, accel_scale=(0.5, 1.5))
    assert tight.fit_accel_gain({}, [0]) == pytest.approx(-0.8 * 1.5)  # clipped to the bounds
    free.accel_scale = None  # from here as simulated, cached apart
    assert free.sse({}, 0) == pytest.approx((0.0, err))
