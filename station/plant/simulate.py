"""Fast whole-run simulation of the SFLR in closed (or open) loop, as the rig runs it.

The plant is stepped in its modal (diagonal) form z_{k+1} = Λ z_k + b_m v[k],
y_k = Re(C_m z_k) (an exact similarity transform of the ZOH model, O(n) per sample
instead of O(n²)), and the sample loop, with the compensator's recursions, saturation
and encoder quantization, runs in a numba-compiled kernel. Without numba the same
kernel runs as plain Python (same results, about 1000x slower).

Timing (ARCHITECTURE.md, DESIGN.md "Timing and log rows"): at tick k the sensors latch
theta[k], a[k] from x_k; the command is v[k] = C(u[k], theta[k-d], a[k-d]) with the
alignment d (v[k] = 0 for k < d, before the first sample); then x_{k+1} = Ad x_k + Bd v[k].
"""

from __future__ import annotations

import math

import numpy as np

from station import DT

try:  # compiled kernel when numba is installed; plain Python otherwise
    import numba
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None


def _commit(num, den, xs, ys, x, y):  # pragma: no cover - compiled by numba
    """Push input x and output y into a direct-form I history; return the next
    output's history term sum(num[i] x[k+1-i]) - sum(den[i] y[k+1-i]) (i >= 1),
    summed in the order of station.control.DiscreteTF."""
    for i in range(xs.shape[0] - 1, 0, -1):
        xs[i] = xs[i - 1]
    if xs.shape[0] > 0:
        xs[0] = x
    for i in range(ys.shape[0] - 1, 0, -1):
        ys[i] = ys[i - 1]
    if ys.shape[0] > 0:
        ys[0] = y
    acc = 0.0
    for i in range(xs.shape[0]):
        acc += num[i + 1] * xs[i]
    for i in range(ys.shape[0]):
        acc -= den[i + 1] * ys[i]
    return acc


def _loop(lam, bm, cm, z0, u, v_open, use_v_open, closed, gnum, gden, anum, aden, use_ga,
          limit, d, quantize, cmd_mode):  # pragma: no cover - compiled by numba
    n = u.shape[0]
    theta = np.zeros(n)
    acc = np.zeros(n)
    v = np.zeros(n)
    thd = np.zeros(n)
    z = z0.copy()
    m = z.shape[0]
    gx = np.zeros(gnum.shape[0] - 1)  # Gth input history (newest first)
    gy = np.zeros(gden.shape[0] - 1)  # Gth output history: the saturated v
    ax = np.zeros(anum.shape[0] - 1)  # Ga input history
    ay = np.zeros(aden.shape[0] - 1)  # Ga output history
    g_acc = 0.0
    a_acc = 0.0
    for k in range(n):
        y0 = 0.0
        y1 = 0.0
        for i in range(m):
            y0 += (cm[0, i] * z[i]).real
            y1 += (cm[1, i] * z[i]).real
        if quantize:
            y0 = math.floor(y0 + 0.5)
            y1 = math.floor(y1 + 0.5)
        theta[k] = y0
        acc[k] = y1
        j = k - d
        uk = u[k]
        td = uk
        e = 0.0
        if use_v_open:
            vk = v_open[k]
        elif k < d:
            vk = 0.0  # no sample yet: the device outputs 0 (v1 tick 0), the filters stay at rest
        else:
            if closed:
                if use_ga:
                    g = anum[0] * acc[j] + a_acc
                    a_acc = _commit(anum, aden, ax, ay, acc[j], g)
                    td = uk - g
                e = td - theta[j]
                vk = gnum[0] * e + g_acc
            else:
                vk = uk
            if vk > limit:
                vk = limit
            elif vk < -limit:
                vk = -limit
            if closed:
                g_acc = _commit(gnum, gden, gx, gy, e, vk)
        v[k] = vk
        thd[k] = td
        # what the device applies: whole DAC counts (the controller keeps the unrounded v)
        if cmd_mode == 1:
            vk = math.floor(vk + 0.5) if vk >= 0.0 else -math.floor(-vk + 0.5)
        elif cmd_mode == 2:
            vk = float(math.trunc(vk))
        for i in range(m):
            z[i] = lam[i] * z[i] + bm[i] * vk
    return theta, acc, v, thd


if numba is not None:
    _commit = numba.njit(cache=True, nogil=True)(_commit)
    _kernel = numba.njit(cache=True, nogil=True)(_loop)
else:  # pragma: no cover
    _kernel = _loop

COMPILED = numba is not None
"""True when the sample loop runs compiled (numba installed)."""


def _coeffs(tf) -> tuple[np.ndarray, np.ndarray]:
    if tf is None:
        return np.zeros(1), np.ones(1)
    num = np.asarray(tf.num, dtype=float)
    den = np.asarray(tf.den, dtype=float)
    if den[0] != 1.0:
        num, den = num / den[0], den / den[0]
    return np.ascontiguousarray(num), np.ascontiguousarray(den)


COMMAND_QUANTIZATION = {"none": 0, "round": 1, "trunc": 2}
"""How a device turns the station's v into DAC counts: v1 rounds (halves away from zero),
the rig's legacy firmware truncates toward zero (spec/protocol.md)."""


def simulate(plant, controller, u, alignment: int = 1, v_open=None, quantize: bool = True,
             command: str = "none") -> dict:
    """Simulate a whole run of the plant with a compensator, as the rig runs it.

    Starts from the plant's current state (at rest after ``plant.reset()``) and the
    controller's filters at rest; neither object is changed.

    Parameters
    ----------
    plant : station.plant.DiscretePlant
        The sampled plant (its modal form is computed once and cached on it).
    controller : station.control.Compensator or station.control.OpenLoop
        Uses its ``gth``, ``ga`` (DiscreteTF or None, coefficients in z⁻¹, den[0] = 1)
        and ``limit`` (DAC counts or None). ``gth is None`` means open loop, v = u
        clamped at ±limit.
    u : array_like, shape (N,)
        Reference per tick: encoder counts (closed loop) or DAC counts (open loop).
    alignment : int, default 1
        Computational delay d >= 0: v[k] = C(u[k], theta[k-d], a[k-d]). For k < d there
        is no sample to compute from: v[k] = 0 and the controller is not stepped, as on
        the device (v1 tick 0 outputs 0) and in :func:`station.loop.run_loop`.
    v_open : array_like, shape (N,), optional
        When given, the command applied at each tick (e.g. a log's v); the controller
        is not used and theta_d_hat = u.
    quantize : bool, default True
        Round theta and a to whole counts as the rig's sensors do (no noise added; see
        `Sensors` for a noisy accelerometer).
    command : {"none", "round", "trunc"}, default "none"
        How the device turns v into whole DAC counts before it acts on the plant:
        "round" (protocol v1, halves away from zero), "trunc" (the legacy firmware,
        toward zero), "none" (v acts unrounded). The returned v is the controller's.

    Returns
    -------
    dict of ndarray, shape (N,)
        ``t`` (s, k·dt), ``u``, ``v`` (DAC counts, after the clamp), ``theta`` (encoder
        counts), ``a`` (accelerometer counts), ``theta_d_hat`` (encoder counts).

    Raises
    ------
    ValueError
        Negative alignment, v_open of a different length than u, or an unknown
        ``command``.
    """
    if command not in COMMAND_QUANTIZATION:
        raise ValueError(f"command quantization must be one of {', '.join(COMMAND_QUANTIZATION)}, got {command!r}")
    u = np.ascontiguousarray(np.asarray(u, dtype=float).ravel())
    d = int(alignment)
    if d < 0:
        raise ValueError(f"alignment must be >= 0, got {alignment}")
    use_v_open = v_open is not None
    if use_v_open:
        v_open = np.ascontiguousarray(np.asarray(v_open, dtype=float).ravel())
        if v_open.shape != u.shape:
            raise ValueError(f"v_open has {v_open.size} samples, u has {u.size}")
    else:
        v_open = np.zeros(1)
    lam, bm, cm, vinv = plant.modal_form()
    z0 = vinv @ plant.x.astype(complex)
    gth = getattr(controller, "gth", None)
    ga = getattr(controller, "ga", None)
    limit = getattr(controller, "limit", None)
    gnum, gden = _coeffs(gth)
    anum, aden = _coeffs(ga)
    theta, a, v, thd = _kernel(
        lam, bm, np.ascontiguousarray(cm), z0, u, v_open, use_v_open, gth is not None,
        gnum, gden, anum, aden, ga is not None, math.inf if limit is None else float(limit), d, bool(quantize),
        COMMAND_QUANTIZATION[command],
    )
    dt = getattr(plant, "dt", DT)
    return {"t": np.arange(u.size) * dt, "u": u, "v": v, "theta": theta, "a": a, "theta_d_hat": thd}
