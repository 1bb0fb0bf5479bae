"""The blind plant's sub-step integrator for its nonlinear motor and drive train (numba).

Between two samples the amplifier's command is held; the plant's linear part (FEM, motor
inertia and damping, viscous friction, any spring to ground) is stepped exactly by the
zero-order-hold matrices of a sub-step, and the nonlinear torques are held over each sub-step:

- backlash: the drive train's spring and damper transmit nothing while the motor - base
  angle is within +-gap/2 (a plant variant without them); beyond it the spring acts on the
  angle minus gap/2 (a constant offset torque added to the linear spring's);
- cogging: -k_tau*c*sin(N*motor angle) on the motor;
- dry friction with stick-slip: a still motor is held (exact variant with its angle and
  zero speed frozen) until the net torque on it exceeds the breakaway level F_s = k_tau*v_s;
  it then slides against k_tau*(v_c + (v_s - v_c)*exp(-(w/w_s)^2))*sign(w) (Stribeck; with
  v_s = v_c plain Coulomb friction); a motor whose speed reaches or crosses zero within a
  sub-step is set still and held, and breaks away again (either way) at the start of a later
  sub-step only if the net torque then exceeds F_s.

The Stribeck term's slope is a negative damping of up to k_tau*(v_s - v_c)*0.858/w_s, far
stiffer than anything else on the motor when w_s is small. While the motor slides slower
than :data:`BAND` * w_s (and for the sub-step in which it breaks away) a sub-step is split
into ``micro`` equal micro-steps with their own exact matrices, so that the Stribeck
torque is resolved; faster than that the Stribeck term is below exp(-16) of its height.

State layout: x = (q, q') of the FEM's DOFs (motor angle first, base angle second);
``st`` = [stuck (1.0 or 0.0), sliding direction (+-1.0)], updated in place.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

BAND = 4.0
"""Micro-steps while the sliding motor is slower than BAND * stribeck_speed."""

# indices into the configuration vector ``cfg``
KD, CD, GAP2, FC, FS, WS, COG, COGN, KTAU = range(9)


def config(kd: float, cd: float, gap2: float, fc: float, fs: float, ws: float, cog: float, cogn: float,
           ktau: float) -> np.ndarray:
    """The kernel's configuration vector.

    Parameters
    ----------
    kd, cd : float
        Drive-train spring (N*m/rad) and damper (N*m*s/rad).
    gap2 : float
        Half the backlash gap, rad (0: none).
    fc, fs : float
        Sliding (Coulomb) and breakaway friction torques, N*m (fs >= fc; fs = 0: no friction).
    ws : float
        Stribeck speed, rad/s of the motor.
    cog : float
        Cogging torque amplitude, N*m (0: none).
    cogn : float
        Cogging cycles per revolution of the motor angle.
    ktau : float
        Torque per DAC count, N*m.
    """
    return np.array([kd, cd, gap2, fc, fs, ws, cog, cogn, ktau], dtype=np.float64)


@njit(cache=True)
def _drive(x, cfg):
    """(drive train transmits, its spring's offset torque on the motor, cogging torque)."""
    delta = x[0] - x[1]
    coupled, offset, cog = True, 0.0, 0.0
    if cfg[GAP2] > 0.0:
        if abs(delta) <= cfg[GAP2]:
            coupled = False
        else:  # engaged: the spring acts on delta -+ gap/2; the linear part has kd*delta
            offset = cfg[KD] * math.copysign(cfg[GAP2], delta)
    if cfg[COG] != 0.0:
        cog = -cfg[COG] * math.sin(cfg[COGN] * x[0])
    return coupled, offset, cog


@njit(cache=True)
def _net_on_still_motor(x, v, cfg, nd, coupled, offset, cog):
    """Torque on the motor were it still: amplifier + cogging - drive train (spring, damper)."""
    drive = 0.0
    if coupled:
        drive = cfg[KD] * (x[0] - x[1]) - offset + cfg[CD] * (0.0 - x[nd + 1])
    return cfg[KTAU] * v + cog - drive


@njit(cache=True)
def _step(x, y, v, st, phi, gam, cfg, nd):
    """One step from ``x`` into ``y`` with the nonlinear torques held; ``phi``/``gam`` hold
    the four variants (index 2*coupled + stuck). Updates ``st``."""
    coupled, offset, cog = _drive(x, cfg)
    f_m, f_b = offset + cog, -offset
    fs = cfg[FS]
    if fs > 0.0:
        if st[0] != 0.0:
            net = _net_on_still_motor(x, v, cfg, nd, coupled, offset, cog)
            if abs(net) > fs:
                st[0] = 0.0
                st[1] = math.copysign(1.0, net)
        if st[0] == 0.0:
            fc = cfg[FC]
            level = fc
            if fs > fc:
                r = x[nd] / cfg[WS]
                level = fc + (fs - fc) * math.exp(-r * r)
            f_m -= st[1] * level
    k = (2 if coupled else 0) + (1 if st[0] != 0.0 else 0)
    P, G = phi[k], gam[k]
    for i in range(x.shape[0]):
        acc = G[i, 0] * v + G[i, 1] * f_m + G[i, 2] * f_b
        for j in range(x.shape[0]):
            acc += P[i, j] * x[j]
        y[i] = acc
    if fs > 0.0 and st[0] == 0.0 and y[nd] * st[1] <= 0.0:
        y[nd] = 0.0  # the motor stopped within the step: it sticks
        st[0] = 1.0


@njit(cache=True)
def advance(x, v, st, phi, gam, fphi, fgam, cfg, nd, steps, micro, band):
    """One sample: ``steps`` sub-steps of the held command ``v`` (DAC counts after the amplifier).

    Parameters
    ----------
    x : array, shape (2*nd,)
        State at the start of the sample.
    v : float
        Command, DAC counts (torque k_tau*v).
    st : array, shape (2,)
        [stuck, direction]; updated in place.
    phi, gam : arrays, shapes (4, 2*nd, 2*nd) and (4, 2*nd, 3)
        Exact ZOH matrices of a sub-step per variant (2*coupled + stuck); the inputs are
        (v, extra motor torque, extra base torque).
    fphi, fgam : arrays
        The same for a micro-step (a sub-step / ``micro``).
    cfg : array
        :func:`config`.
    nd : int
        DOFs (the state has 2*nd).
    steps, micro : int
        Sub-steps per sample; micro-steps per refined sub-step (1: never refine).
    band : float
        Refine while the sliding motor's |speed| is below this, rad/s.

    Returns
    -------
    array, shape (2*nd,)
        The state at the end of the sample.
    """
    a, b = x.copy(), np.empty_like(x)
    for _ in range(steps):
        fine = False
        if micro > 1:
            if st[0] == 0.0:
                fine = abs(a[nd]) < band
            else:  # still: refine the sub-step in which it breaks away
                coupled, offset, cog = _drive(a, cfg)
                fine = abs(_net_on_still_motor(a, v, cfg, nd, coupled, offset, cog)) > cfg[FS]
        if fine:
            for _ in range(micro):
                _step(a, b, v, st, fphi, fgam, cfg, nd)
                a, b = b, a
        else:
            _step(a, b, v, st, phi, gam, cfg, nd)
            a, b = b, a
    return a
