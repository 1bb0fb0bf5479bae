"""The modal (diagonal) form of the exact-ZOH linear plant, the simulation kernel's input.

z = V⁻¹ x: the sampled plant x_{k+1} = Ad x_k + Bd v[k] becomes z ← Λ z + b_m v per step,
y = Re(C_m z), an exact similarity transform that costs O(n) per step instead of O(n²).
:func:`linear_form` builds it for a parameter set (cached), on the sample grid or on a
sub-step grid dt/M with the extra outputs that friction and backlash need;
:func:`sampled_form` takes it from a `DiscretePlant` as it is.

Imports fem, discrete and parameters only (below :mod:`station.plant.model` and
:mod:`station.plant.simulate`, which use it).
"""

from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import numpy as np

# scipy.linalg / scipy.signal / scipy.optimize / python-control are imported where used:
# they cost seconds, and a run's first tick does not need them (start-up time).

from station.plant.diskcache import cached_arrays, use_disk
from station.plant.discrete import DiscretePlant
from station.plant.fem import modal_basis, realization
from station.plant.parameters import Params


class LinearForm(NamedTuple):
    """Diagonal (modal) form of the exact-ZOH linear plant on a (sub-)step grid.

    The state in modal coordinates z (complex, shape (n,)) evolves per step of
    h = dt / substeps as z ← lam·z + bm·v + bp·T, v in DAC counts (torque k_tau·v on the
    motor), T an extra torque pair, N·m, +T on the motor and −T on the base.

    Attributes
    ----------
    lam, bm, bp : ndarray of complex, shape (n,)
    cm : ndarray of complex, shape (2, n)
        Sample outputs Re(cm @ z): theta (encoder counts), a (accelerometer counts).
    co : ndarray of complex, shape (4, n)
        Re(co @ z): δ = θ_motor − θ_base (rad), δ' (rad/s), ω_motor (rad/s), and
        ω_motor after one free step (rows of co[2]·lam). Zero when ``substeps`` is 0.
    vinv : ndarray of complex, shape (n, n)
        Maps a state of `fem.state_matrices` into z. With sub-steps only one mode of
        each complex-conjugate pair is kept (the state is real), its outputs counted
        twice in cm and co, so n is about half the state count.
    gw_v, gw_p : float
        Change of ω_motor over one step per DAC count and per N·m of T.
    substeps : int
        Steps per sample; 0: sampled at dt by `DiscretePlant.modal_form` (no friction
        or backlash: exactly today's plant), with bp and co zero.
    """

    lam: np.ndarray
    bm: np.ndarray
    bp: np.ndarray
    cm: np.ndarray
    co: np.ndarray
    vinv: np.ndarray
    gw_v: float
    gw_p: float
    substeps: int


def sampled_form(plant: DiscretePlant) -> LinearForm:
    """The :class:`LinearForm` of a `DiscretePlant` at its own dt (``substeps`` 0).

    Parameters
    ----------
    plant : DiscretePlant
        Its cached :meth:`~station.plant.DiscretePlant.modal_form` is used as it is.

    Returns
    -------
    LinearForm
        bp and co zero (no friction or backlash on the sample grid).
    """
    lam, bm, cm, vinv = plant.modal_form()
    n = lam.size
    return LinearForm(lam, bm, np.zeros(n, complex), np.ascontiguousarray(cm), np.zeros((4, n), complex), vinv,
                      0.0, 0.0, 0)


@functools.lru_cache(maxsize=256)
def linear_form(params: Params, n_elements: int, dt: float, substeps: int) -> LinearForm:
    """The (cached) :class:`LinearForm` of a parameter set.

    Cached in memory and, outside a :func:`station.plant.diskcache.bulk` block (a
    diagnosis), on disk (keyed by the parameter values,
    the element count, dt, the sub-steps and the plant's code): a warm start neither
    imports scipy nor decomposes anything, and gets the same bits.

    Parameters
    ----------
    params : Params
    n_elements : int
    dt : float
        Sample time, s.
    substeps : int
        0: sampled at dt exactly as `DiscretePlant` (bp, co zero); M >= 1: sub-step
        grid dt / M with the outputs friction and backlash need.
    """
    parts = (*(getattr(params, f.name) for f in dataclasses.fields(params)), int(n_elements), float(dt),
             int(substeps))
    def compute():
        return _form_arrays(_linear_form(params, n_elements, dt, substeps))

    arrays = cached_arrays("linear-form", parts, compute) if use_disk() else compute()
    return LinearForm(*(arrays[name] if arrays[name].ndim else arrays[name].item() for name in LinearForm._fields))


def _form_arrays(form: LinearForm) -> dict[str, np.ndarray]:
    return {name: np.asarray(value) for name, value in zip(LinearForm._fields, form)}


def _linear_form(params: Params, n_elements: int, dt: float, substeps: int) -> LinearForm:
    """:func:`linear_form` computed (not cached)."""
    if substeps == 0:
        return sampled_form(DiscretePlant(params, n_elements, dt))
    basis = modal_basis(params, n_elements)
    A, B, C = realization(params, basis)
    m, Phi, _, scale = basis
    n_dof = Phi.shape[0]
    pair = np.zeros(n_dof)
    pair[0], pair[m.base] = 1.0, -1.0
    Bp = np.concatenate([np.zeros(n_dof), Phi.T @ pair])
    rows = np.zeros((3, 2 * n_dof))
    rows[0, :n_dof] = (Phi[0] - Phi[m.base]) / scale  # δ = θ_m − θ_b
    rows[1, n_dof:] = Phi[0] - Phi[m.base]             # δ'
    rows[2, n_dof:] = Phi[0]                            # ω_m
    h = dt / substeps
    import scipy.signal  # lazy: start-up time (scipy.signal)
    Ad, Bd, _, _, _ = scipy.signal.cont2discrete((A, np.column_stack([B[:, 0], Bp]), C, np.zeros((2, 2))),
                                                 h, method="zoh")
    import scipy.linalg  # lazy: start-up time (scipy.linalg)
    lam, V = scipy.linalg.eig(Ad)
    vinv = scipy.linalg.lu_solve(scipy.linalg.lu_factor(V), np.eye(V.shape[0]))
    # the state is real: keep one of each conjugate pair (LAPACK returns exact conjugates)
    # and count its output twice, which halves the work per sub-step
    keep = lam.imag >= 0.0
    weight = np.where(lam.imag > 0.0, 2.0, 1.0)[keep]
    lam, vinv = lam[keep], vinv[keep]
    cm, rows_v = (C @ V)[:, keep] * weight, (rows @ V)[:, keep] * weight
    bm, bp = vinv @ Bd[:, 0], vinv @ Bd[:, 1]
    co = np.vstack([rows_v, rows_v[2] * lam])
    gw_v, gw_p = float((rows_v[2] @ bm).real), float((rows_v[2] @ bp).real)
    return LinearForm(lam, bm, bp, np.ascontiguousarray(cm), np.ascontiguousarray(co), vinv, gw_v, gw_p,
                      int(substeps))


__all__ = ["LinearForm", "linear_form", "sampled_form"]
