"""Linear closed-loop poles of the sampled plant with a compensator (clamp not active).

The rig's loop is v[k] = Gth(θ̂_d − θ)[k] with θ̂_d = u − Ga(a), using the samples of
d ticks earlier (alignment d, DESIGN.md "Timing and log rows"), i.e. in negative
feedback v = −K y with K(z) = z^{−d}·Gth(z)·[1, Ga(z)] and y = [θ, a]. While the
±limit clamp is not reached the loop is this linear system; its poles decide stability.
"""

from __future__ import annotations

import numpy as np

# scipy.linalg / scipy.signal / scipy.optimize / python-control are imported where used:
# they cost seconds, and a run's first tick does not need them (start-up time).


def _tf_z(tf, dt: float) -> control.TransferFunction:
    """A DiscreteTF (coefficients in z⁻¹) as a python-control transfer function in z."""
    num, den = list(tf.num), list(tf.den)
    m = max(len(num), len(den))
    import control  # lazy: start-up time (python-control)
    return control.tf(num + [0.0] * (m - len(num)), den + [0.0] * (m - len(den)), dt)


def closed_loop(plant, controller, alignment: int = 1) -> control.StateSpace:
    """Closed loop of a `DiscretePlant` with a `Compensator`, from u to [θ, a].

    Parameters
    ----------
    plant : DiscretePlant
        The sampled plant (Ad, Bd, Cd, dt).
    controller : station.control.Compensator
        Uses ``gth`` and ``ga`` (DiscreteTF in z⁻¹, ``ga`` may be None); the clamp
        (``limit``) is ignored: this is the small-signal loop.
    alignment : int, default 1
        Computational delay d in samples.

    Returns
    -------
    control.StateSpace
        Discrete (dt = plant.dt) closed loop; input the reference u (counts), outputs
        [θ, a] (counts).

    Raises
    ------
    ValueError
        When the controller has no Gth (open loop).
    """
    if getattr(controller, "gth", None) is None:
        raise ValueError("open loop: no feedback, no closed-loop poles")
    dt = plant.dt
    import control  # lazy: start-up time (python-control)
    P = control.ss(plant.Ad, plant.Bd[:, None], plant.Cd, np.zeros((2, 1)), dt)
    delay = control.tf([1.0], [1.0] + [0.0] * int(alignment), dt) if alignment > 0 else control.tf([1.0], [1.0], dt)
    forward = control.ss(_tf_z(controller.gth, dt) * delay)
    ga = control.ss(_tf_z(controller.ga, dt)) if controller.ga is not None else control.ss([], [], [], [[0.0]], dt)
    mix = control.append(control.ss([], [], [], [[1.0]], dt), ga)
    K = forward * control.ss([], [], [], [[1.0, 1.0]], dt) * mix
    return control.feedback(P, K, sign=-1) * forward


def closed_loop_spectral_radius(plant, controller, alignment: int = 1) -> float:
    """Largest pole magnitude of `closed_loop` (< 1: stable; the loop removes the
    plant's rigid-body integrator). For open loop (no Gth), that of Ad itself.

    Parameters
    ----------
    plant : DiscretePlant
        The sampled plant.
    controller : station.control.Compensator or OpenLoop
        As :func:`closed_loop`.
    alignment : int, default 1
        Computational delay d in samples.
    """
    if getattr(controller, "gth", None) is None:
        return float(np.abs(np.linalg.eigvals(plant.Ad)).max())
    import control  # lazy: start-up time (python-control)
    return float(np.abs(control.poles(closed_loop(plant, controller, alignment))).max())
