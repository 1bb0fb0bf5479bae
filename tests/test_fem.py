"""FEM verification against independent truth: analytical beam theory and thesis Table 3.1.

Analytical Euler–Bernoulli beam (EI, mu, L): ω = (βL)²·sqrt(EI/(mu L⁴)), with βL the
roots of tan βL = tanh βL (pinned-free) and cos βL·cosh βL = −1 (cantilever), found here
by scipy.optimize.brentq; mode shapes from the same closed forms.
"""

from fractions import Fraction

import numpy as np
import pytest
import scipy.optimize

from station.plant import beam_frequencies, beam_modes

# Thesis Table 3.1 as printed: pinned-free uniform beam, EI = mu = L = 1, rad/s.
TABLE_3_1 = {
    1: (17.54438, 70.08705),
    2: (15.51451, 55.82281, 135.55951),
    5: (15.42203, 50.08486, 105.21056),
    10: (15.41846, 49.97323, 104.32186),
    20: (15.41822, 49.96540, 104.25254),
    50: (15.41821, 49.96488, 104.24782),
    100: (15.41821, 49.96486, 104.24770),
}
# The one entry the method does not give; see test_table_3_1_n2_first_entry_is_a_typo.
TABLE_TYPO = {(2, 0): 15.51421}


def _roots(f, guesses):
    return np.array([scipy.optimize.brentq(f, g - 0.3, g + 0.3) for g in guesses])


BETA_PINNED = _roots(lambda b: np.tan(b) - np.tanh(b), [3.9266, 7.0686, 10.2102])
BETA_CANTILEVER = _roots(lambda b: np.cos(b) * np.cosh(b) + 1.0, [1.8751, 4.6941, 7.8548])


def test_analytic_roots_match_textbook_values():
    assert BETA_PINNED == pytest.approx([3.9266, 7.0686, 10.2102], abs=1e-4)
    assert BETA_CANTILEVER == pytest.approx([1.8751, 4.6941, 7.8548], abs=1e-4)


@pytest.mark.parametrize("n", sorted(TABLE_3_1))
def test_table_3_1_to_printed_digits(n):
    omega = beam_frequencies(n, "pinned-free", EI=1.0, mu=1.0, L=1.0)
    for i, printed in enumerate(TABLE_3_1[n]):
        expected = TABLE_TYPO.get((n, i), printed)
        assert round(omega[i], 5) == expected, (n, i, omega[i], printed)


def _det(matrix):
    """Exact determinant (Fraction Gaussian elimination)."""
    a = [row[:] for row in matrix]
    det = Fraction(1)
    for c in range(len(a)):
        p = next(r for r in range(c, len(a)) if a[r][c] != 0)
        if p != c:
            a[c], a[p] = a[p], a[c]
            det = -det
        det *= a[c][c]
        for r in range(c + 1, len(a)):
            f = a[r][c] / a[c][c]
            a[r] = [x - f * y for x, y in zip(a[r], a[c])]
    return det


def test_table_3_1_n2_first_entry_is_a_typo():
    """The table prints 15.51451 for n = 2; the method gives 15.51421.

    Evidence: all 19 other entries are reproduced to every printed digit; the two
    numbers differ in one digit; and the exact (rational-arithmetic) characteristic
    determinant det(K − ω² M) of the 2-element pinned-free model changes sign in
    [15.514205, 15.514215] but not in [15.51446, 15.51456], so 15.51451 is no
    eigenvalue of the 2-element model, whatever the floating point.
    """
    h = Fraction(1, 2)
    k = [[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h],
         [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]]
    m = [[156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
         [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]]
    size = 6
    K = [[Fraction(0)] * size for _ in range(size)]
    M = [[Fraction(0)] * size for _ in range(size)]
    for e in range(2):
        for i in range(4):
            for j in range(4):
                K[2 * e + i][2 * e + j] += k[i][j] / h**3
                M[2 * e + i][2 * e + j] += m[i][j] * h / 420
    free = range(1, size)  # w_0 pinned

    def char(omega):
        lam = Fraction(omega) ** 2
        return _det([[K[i][j] - lam * M[i][j] for j in free] for i in free])

    assert char("15.514205") * char("15.514215") < 0
    assert char("15.51446") * char("15.51456") > 0
    assert round(beam_frequencies(2)[0], 5) == 15.51421


def test_pinned_free_converges_to_analytic_from_above():
    exact = BETA_PINNED**2
    errors = []
    for n in (1, 2, 5, 10, 20, 50, 100):
        omega = beam_frequencies(n)[:3]
        m = min(3, omega.size)
        # Rayleigh–Ritz upper bound, to the eigensolve's rounding: at 100 elements, where the
        # discretization error is ~1.6e-9, one BLAS thread gave -3.2e-9 for the first mode
        assert np.all(omega[:m] >= exact[:m] * (1 - 1e-8))
        errors.append(omega[0] - exact[0])
    assert np.all(np.diff(errors) < 0)
    assert beam_frequencies(100)[:3] == pytest.approx(exact, rel=1e-7)
    # Hermite cubic elements: frequency error O(h^4)
    e10, e20 = (beam_frequencies(n)[:3] - exact for n in (10, 20))
    assert np.log2(e10 / e20) == pytest.approx(4.0, abs=0.1)


def test_frequency_scaling_with_physical_parameters():
    EI, mu, L = 0.21, 0.1366, 0.4135
    omega = beam_frequencies(50, "pinned-free", EI=EI, mu=mu, L=L)[:3]
    assert omega == pytest.approx(BETA_PINNED**2 * np.sqrt(EI / (mu * L**4)), rel=2e-6)
    unit = beam_frequencies(50)[:3]
    assert omega == pytest.approx(unit * np.sqrt(EI / (mu * L**4)), rel=1e-8)


def test_cantilever_against_analytic():
    assert beam_frequencies(100, "cantilever")[:3] == pytest.approx(BETA_CANTILEVER**2, rel=1e-7)
    assert beam_frequencies(20, "cantilever")[:3] == pytest.approx(BETA_CANTILEVER**2, rel=5e-5)
    assert beam_frequencies(4, "cantilever")[0] == pytest.approx(BETA_CANTILEVER[0] ** 2, rel=1e-4)


def _mac(a, b):
    return (a @ b) ** 2 / ((a @ a) * (b @ b))


@pytest.mark.parametrize("bc", ["pinned-free", "cantilever"])
def test_mode_shapes_against_analytic(bc):
    _, x, w = beam_modes(10, bc)
    betas = BETA_PINNED if bc == "pinned-free" else BETA_CANTILEVER
    for i, b in enumerate(betas):
        if bc == "pinned-free":
            exact = np.sin(b * x) + np.sin(b) / np.sinh(b) * np.sinh(b * x)
        else:
            s = (np.cosh(b) + np.cos(b)) / (np.sinh(b) + np.sin(b))
            exact = np.cosh(b * x) - np.cos(b * x) - s * (np.sinh(b * x) - np.sin(b * x))
        exact = exact / np.abs(exact).max() * np.sign(exact[-1])
        assert _mac(w[:, i], exact) > 0.99999
        assert np.abs(w[:, i] - exact).max() < 1e-3


def test_element_count_out_of_range():
    for n in (0, 101, 2.5):
        with pytest.raises(ValueError, match="n_elements"):
            beam_frequencies(n)
    with pytest.raises(ValueError, match="bc"):
        beam_frequencies(4, "clamped-clamped")
