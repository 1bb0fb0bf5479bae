"""The beam's tip in a simulated run: its position and its residual vibration.

DESIGN.md "Designing a compensator on a model": the tip position is the hub angle plus the
beam's tip deflection / L, in encoder counts. The FEM's lateral displacements w are measured
from the line the link had at rest (a rigid turn by α gives w = x·α: the rigid-body mode
of :class:`station.plant.fem.SecondOrderModel`), so that sum is H·w_tip/L: the angle, seen
from the hub's axis, at which the tip is.

The simulation kernel outputs θ and a only. The tip position is another linear output of the
same state, so :func:`tip_position` replays the run's own commands through the same kernel,
effects and all (friction, offsets: the plant's trajectory is a function of the commands
alone), with the output rows Re(cm·z) swapped for the tip position and a: the same float
operations as the run, a row more. The tip's residual vibration is the accelerometer's
(:func:`residual`): its RMS and largest |a| from :data:`RESIDUAL_AFTER_S` after the step to
the run's end.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from station.plant.fem import modal_basis
from station.plant.kernel import COMMAND_QUANTIZATION, coefficients, effects_of, run_kernel
from station.plant.modal import LinearForm
from station.rig import DT, RESIDUAL_AFTER_S  # noqa: F401 (RESIDUAL_AFTER_S: the window, re-exported)

class Residual(NamedTuple):
    """The accelerometer's residual vibration after the step.

    Attributes
    ----------
    rms : float
        RMS of a over the window, accelerometer counts (NaN: the run ends before it).
    peak : float
        Largest |a| over the window, accelerometer counts.
    """

    rms: float
    peak: float


def residual(a, step_tick: int, dt: float = DT, after_s: float = RESIDUAL_AFTER_S) -> Residual:
    """RMS and peak of the accelerometer from ``after_s`` after the step to the run's end.

    Parameters
    ----------
    a : array_like, shape (N,)
        Tip acceleration, accelerometer counts.
    step_tick : int
        The step's tick.
    dt : float
        Sample time, s.
    after_s : float
        Start of the window, s after the step.

    Returns
    -------
    Residual
        RMS and peak |a| over the window, accelerometer counts; both NaN when the run ends
        before the window starts.
    """
    a = np.asarray(a, dtype=float)
    tail = a[step_tick + int(round(after_s / dt)):]
    if tail.size == 0:
        return Residual(math.nan, math.nan)
    return Residual(float(np.sqrt(np.mean(tail * tail))), float(np.max(np.abs(tail))))


def tip_row(params, n_elements: int) -> np.ndarray:
    """The tip position as a row over :func:`station.plant.fem.state_matrices`' state.

    Parameters
    ----------
    params : station.plant.parameters.Params
        The linear part's parameters (H, L).
    n_elements : int
        Beam elements.

    Returns
    -------
    ndarray, shape (2·n_dof,)
        tip = row @ x, encoder counts: H·w_tip/L with w_tip = Φ[tip_w]·S⁻¹·x[:n_dof].
    """
    m, phi, _, scale = modal_basis(params, n_elements)
    n_dof = phi.shape[0]
    row = np.zeros(2 * n_dof)
    row[:n_dof] = params.H * phi[m.tip_w] / scale / params.L
    return row


def tip_form(form: LinearForm, row: np.ndarray) -> LinearForm:
    """A modal form whose first output is ``row @ x`` instead of θ (a kept).

    The form keeps V⁻¹ only (with sub-steps, one mode of each complex-conjugate pair, its
    outputs counted twice); V is rebuilt from it, the dropped conjugate rows put back.

    Parameters
    ----------
    form : LinearForm
    row : ndarray, shape (n_x,)
        An output row over the state of :func:`station.plant.fem.state_matrices`.

    Returns
    -------
    LinearForm
        ``form`` with its output matrix ``cm`` (complex, shape (2, n_modes)) replaced: row 0 the
        modal form of ``row``, row 1 the accelerometer's as before.
    """
    vinv = np.asarray(form.vinv)
    if form.substeps == 0:
        out = row @ np.linalg.inv(vinv)
    else:
        pair = form.lam.imag > 0.0
        v = np.linalg.inv(np.vstack([vinv, np.conj(vinv[pair])]))
        out = (row @ v[:, :vinv.shape[0]]) * np.where(pair, 2.0, 1.0)
    cm = np.ascontiguousarray(np.vstack([out, form.cm[1]]).astype(complex))
    return form._replace(cm=cm)


@functools.lru_cache(maxsize=64)
def _model_tip_form(model, dt: float) -> LinearForm:
    p = model.linear_params()
    return tip_form(model.linear_form(dt), tip_row(p, model.n_elements))


def tip_position(model, v, dt: float = DT, command: str = "round") -> np.ndarray:
    """The tip position over a run, from the run's commands (module docstring).

    Parameters
    ----------
    model : station.plant.model.Model
        The model the run was simulated on (hashable: its tip form is cached).
    v : array_like, shape (N,)
        The run's commands, DAC counts (the controller's, before the device's quantization).
    dt : float
        Sample time, s.
    command : {"none", "round", "trunc"}
        The device's command quantization, as the run's.

    Returns
    -------
    ndarray, shape (N,)
        Tip position, encoder counts (not quantized: no sensor reads it).
    """
    form = _model_tip_form(model, float(dt))
    v = np.ascontiguousarray(np.asarray(v, dtype=float))
    gnum, gden = coefficients(None)
    tip, _, _, _ = run_kernel(form.lam, form.bm, form.bp, form.cm, form.co, form.gw_v, form.gw_p, form.substeps,
                              np.zeros(form.lam.size, complex), v, v, True, False, gnum, gden, gnum, gden, False,
                              math.inf, 0, False, COMMAND_QUANTIZATION[command], 0, *effects_of(model))
    return tip
