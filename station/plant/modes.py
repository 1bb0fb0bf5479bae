"""Natural frequencies, damping and theta/v antiresonances of the SFLR FEM model.

These are the numbers the rig's measurements can be compared with (DESIGN.md "Measured
dynamics": first beam mode 2.52 Hz with ζ ≈ 0.005 with the hub held, second ≈ 18 Hz;
θ/v antiresonances ≈ 2.5 Hz and 17.7 Hz).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

# scipy.linalg / scipy.signal / scipy.optimize / python-control are imported where used:
# they cost seconds, and a run's first tick does not need them (start-up time).

from station.plant.fem import SecondOrderModel, state_matrices
from station.plant.parameters import Params


@dataclass(frozen=True)
class ModalSummary:
    """Modal numbers of the SFLR model (all frequencies in Hz, ascending).

    Attributes
    ----------
    n_elements : int
        Element count of the model.
    frequencies_hz, damping : ndarray, shape (m,)
        Damped natural frequencies |Im λ|/2π and damping ratios −Re λ/|λ| of the
        oscillatory poles of the whole model (motor free, driven by v).
    antiresonances_hz, antiresonance_damping : ndarray, shape (r,)
        The same for the complex zeros of θ/v (base angle per command). They are the
        modes of the model with the base held still (the beam on its clamp
        spring/damper; the motor then only adds real roots), i.e. also the rig's
        "hub held" beam modes.
    """

    n_elements: int
    frequencies_hz: np.ndarray
    damping: np.ndarray
    antiresonances_hz: np.ndarray
    antiresonance_damping: np.ndarray


def _oscillatory(roots: np.ndarray, max_hz: float) -> tuple[np.ndarray, np.ndarray]:
    roots = roots[np.isfinite(roots)]
    roots = roots[(roots.imag > 1e-6 * np.maximum(np.abs(roots), 1.0)) & (roots.imag / (2 * np.pi) <= max_hz)]
    roots = roots[np.argsort(roots.imag)]
    return roots.imag / (2 * np.pi), -roots.real / np.abs(roots)


def modal_summary(params: Params, n_elements: int = 4, max_hz: float = 200.0) -> ModalSummary:
    """Natural frequencies, damping ratios and θ/v antiresonances of the model.

    Parameters
    ----------
    params : Params
        Parameter set.
    n_elements : int, default 4
        Element count, 1..100.
    max_hz : float, default 200
        Only frequencies up to this are reported (the FEM's highest modes are
        discretization artefacts, and the rig is sampled at 500 Hz).

    Returns
    -------
    ModalSummary
        Poles from the eigenvalues of A (scipy.linalg.eigvals). The zeros of θ/v are
        the eigenvalues of the model with the base angle constrained to zero (output
        zeroing); computed that way they stay accurate at 100 elements, where the
        generic invariant-zero solver (control.zeros) loses digits.
    """
    A, _, _ = state_matrices(params, n_elements)
    import scipy.linalg  # lazy: start-up time (scipy.linalg)
    f, z = _oscillatory(scipy.linalg.eigvals(A), max_hz)
    return ModalSummary(int(n_elements), f, z, *hub_held_modes(params, n_elements, max_hz))


class HubHeldModes(NamedTuple):
    """The beam's modes with the base held still (:func:`hub_held_modes`).

    Attributes
    ----------
    frequencies_hz, damping : ndarray, shape (r,)
        Damped natural frequencies (Hz, ascending) and damping ratios.
    """

    frequencies_hz: np.ndarray
    damping: np.ndarray


def hub_held_modes(params: Params, n_elements: int = 4, max_hz: float = 200.0) -> HubHeldModes:
    """The hub-held beam modes alone: :func:`modal_summary`'s ``antiresonances_hz`` and
    ``antiresonance_damping`` (the same numbers, without the whole model's poles, which a
    search over the beam's damping does not need).

    Parameters
    ----------
    params : Params
    n_elements : int, default 4
    max_hz : float, default 200

    Returns
    -------
    HubHeldModes
        The complex zeros of θ/v (eigenvalues of :func:`base_held_matrix`,
        scipy.linalg.eigvals) up to ``max_hz``.
    """
    import scipy.linalg  # lazy: start-up time (scipy.linalg)
    return HubHeldModes(*_oscillatory(scipy.linalg.eigvals(base_held_matrix(params, n_elements)), max_hz))


def base_held_matrix(params: Params, n_elements: int = 4) -> np.ndarray:
    """State matrix of the model with the base angle held at zero.

    Parameters
    ----------
    params : Params
        Parameter set.
    n_elements : int
        Element count, 1..100.

    Returns
    -------
    ndarray, shape (2 (n_dof - 1), 2 (n_dof - 1))
        First-order form of M q'' + C q' + K q = 0 over all DOFs but the base angle;
        its eigenvalues are the zeros of θ/v.
    """
    m = SecondOrderModel(params, n_elements)
    keep = np.delete(np.arange(m.M.shape[0]), m.base)
    M, Cm, K = (X[np.ix_(keep, keep)] for X in (m.M, m.C, m.K))
    n = keep.size
    return np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, Cm)]])


def with_beam_damping(params: Params, zeta: float, n_elements: int = 4) -> Params:
    """The parameter set with the Rayleigh beam damping that gives a first-mode ζ.

    DESIGN.md's ``beam_damping`` effect: the total damping ratio of the first beam mode
    with the motor and base held still, reached by stiffness-proportional damping of
    the beam elements (C_beam = beam_beta·K_beam). The ratio grows monotonically with
    beam_beta; it is solved for by scipy.optimize.brentq.

    Parameters
    ----------
    params : Params
        Parameter set (its own beam_beta is replaced).
    zeta : float
        Target damping ratio of the first hub-held mode, 1 (tmm-fit with beam_beta = 0:
        0.0054 from the clamp damper alone).
    n_elements : int, default 4
        Element count of the model the value is meant for.

    Returns
    -------
    Params
        A copy with ``beam_beta`` set, s.

    Raises
    ------
    ValueError
        zeta below the clamp damper's own contribution or above 0.5, or no oscillating
        hub-held mode at all.
    """
    def first_zeta(beta: float) -> float:
        p = dataclasses.replace(params, beam_beta=beta)
        zetas = hub_held_modes(p, n_elements).damping
        return float(zetas[0]) if zetas.size else 1.0  # no oscillating mode left: overdamped

    if hub_held_modes(params if params.beam_beta == 0 else dataclasses.replace(params, beam_beta=0.0),
                      n_elements).damping.size == 0:
        raise ValueError("no oscillating hub-held beam mode in this parameter set: no beam damping to set")
    floor = first_zeta(0.0)
    if not floor <= zeta <= 0.5:
        raise ValueError(f"first-mode damping ratio {zeta} out of reach: {floor:.4g} (no beam damping) .. 0.5")
    if zeta == floor:
        return dataclasses.replace(params, beam_beta=0.0)
    hi = 1e-4
    while first_zeta(hi) < zeta:
        hi *= 4.0
    import scipy.optimize  # lazy: start-up time (scipy.optimize)
    beta = scipy.optimize.brentq(lambda b: first_zeta(b) - zeta, 0.0, hi, xtol=1e-14, rtol=1e-12)
    return dataclasses.replace(params, beam_beta=beta)
