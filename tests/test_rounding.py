"""Rounding halves away from zero: the one helper, its compiled twin and the codec that uses it."""

import math

import numpy as np
import pytest

from station.protocol import v1
from station.rounding import half_away, half_away_compiled, round_half_away, sensor_count, sensor_counts

TINY_BELOW_HALF = 0.49999999999999994  # the float just below 0.5: floor(x + 0.5) gives 1

# x, the rule's answer worked out by hand
EDGES = [
    (0.5, 1.0), (-0.5, -1.0), (TINY_BELOW_HALF, 0.0), (-TINY_BELOW_HALF, -0.0), (2.5, 3.0), (-2.5, -3.0),
    (32767.5, 32768.0), (-32767.5, -32768.0), (1.5, 2.0), (-1.5, -2.0), (2.4999999999999996, 2.0),
    (0.0, 0.0), (-0.0, -0.0), (1e-300, 0.0), (4503599627370495.5, 4503599627370496.0), (2.0**53 + 2, 2.0**53 + 2),
    (1e300, 1e300), (math.inf, math.inf), (-math.inf, -math.inf),
]


@pytest.mark.parametrize("x, expected", EDGES)
def test_edge_cases_by_hand(x, expected):
    assert half_away(x) == expected
    assert half_away_compiled(x) == expected


def test_an_arrays_reading_is_each_elements_by_the_one_rule():
    # the edges by hand, random values, exact halves and the floats just inside them
    rng = np.random.default_rng(12)
    xs = np.concatenate([[x for x, _ in EDGES], [math.nan], rng.uniform(-40000, 40000, 5000),
                         np.round(rng.uniform(-1000, 1000, 2000)) + 0.5,
                         np.nextafter(np.round(rng.uniform(-1000, 1000, 2000)) + 0.5, 0.0)])
    got = sensor_counts(xs.reshape(-1, 1)).ravel()  # any shape
    want = np.array([sensor_count(float(x)) for x in xs])
    np.testing.assert_array_equal(got, want)
    assert not np.any(np.signbit(got[got == 0.0]))  # a count has no sign
    assert sensor_counts(np.array([TINY_BELOW_HALF]))[0] == 0.0  # where floor(x + 0.5) gives 1


def test_nan_stays_nan():
    assert math.isnan(half_away(math.nan)) and math.isnan(half_away_compiled(math.nan))


def test_compiled_twin_equals_the_helper_on_random_values():
    rng = np.random.default_rng(11)
    xs = np.concatenate([rng.uniform(-40000, 40000, 20000),
                         np.round(rng.uniform(-1000, 1000, 5000)) + 0.5,  # exact halves
                         np.nextafter(np.round(rng.uniform(-1000, 1000, 5000)) + 0.5, 0.0),  # just inside
                         rng.standard_normal(5000) * 1e-3])
    for x in xs:
        x = float(x)
        assert half_away_compiled(x) == half_away(x), x
        # independent truth: exact decimal arithmetic
        assert half_away(x) == _decimal_rule(x), x


def _decimal_rule(x: float) -> float:
    from decimal import ROUND_HALF_UP, Decimal

    return float(Decimal(x).quantize(Decimal(1), rounding=ROUND_HALF_UP))  # HALF_UP is away from zero


def test_round_half_away_is_an_int():
    assert round_half_away(-2.5) == -3 and isinstance(round_half_away(2.5), int)
    assert round_half_away(TINY_BELOW_HALF) == 0


def test_round_command_clamps_then_rounds():
    assert v1.round_command(32767.5) == 32767 and v1.round_command(-32767.5) == -32768
    assert v1.round_command(-TINY_BELOW_HALF) == 0


@pytest.mark.parametrize("v, moves", [(TINY_BELOW_HALF, False), (0.5, True), (-TINY_BELOW_HALF, False), (-0.5, True)])
def test_simulate_rounds_commands_as_the_device(v, moves):
    """The compiled kernel sends what the v1 device applies: 0 for just under a half, ±1 at ±0.5."""
    from station.plant import load_model
    from station.plant.simulate import simulate

    n = 200
    r = simulate(load_model(), None, np.zeros(n), v_open=np.full(n, v), command="round")
    assert (np.abs(r["theta"]).max() > 0) == moves
