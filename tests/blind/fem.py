"""The SFLR plant for the blind generator: FEM assembly from DESIGN.md "FEM plant" alone.

DOFs (SI units, rotational DOFs not scaled by the element length): motor angle, base
angle, beam root slope, then (w, phi) at beam nodes 1..n (root lateral displacement
pinned). Hermite cubic Euler-Bernoulli elements with consistent mass; drive train (motor ->
base) and clamp (base -> beam root) are torsional spring/dampers; the accelerometer is a
point mass + rotary inertia at the tip node; the motor is J_m = k_tau/num with viscous
damping c_m = act_p*J_m, driven by the torque k_tau*v.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

H = 1024 / (2 * math.pi)
"""Encoder counts per radian at the base."""

K_TAU = 0.0106886520727539
"""Motor torque per DAC count, N*m/count (fixed constant of the parameter set)."""


@dataclass(frozen=True)
class Params:
    """Parameter set "tmm-fit" (DESIGN.md table; SI units)."""

    mu: float = 0.13663958779898777
    L: float = 0.41354375
    EI: float = 0.2099999014730539
    drive_k: float = 0.10272834719157942
    drive_c: float = 0.09564528653323137
    clamp_k: float = 2.4977992
    clamp_c: float = 0.003897076
    J_base: float = 0.0016121636
    m_accel: float = 0.006126102297970537
    J_accel: float = 7.0627e-07
    act_K: float = 0.06727320631008038
    act_p: float = 120.40659975047289
    a_gain: float = 1.1452654922936827

    def scaled(self, ratios: dict[str, float]) -> Params:
        """A copy with each named parameter multiplied by its ratio (param:NAME effects)."""
        return replace(self, **{name: getattr(self, name) * r for name, r in ratios.items()})


# DOF indices
MOTOR, BASE, ROOT = 0, 1, 2


def tip_w(n_elements: int) -> int:
    """Index of the tip's lateral displacement DOF."""
    return 3 + 2 * (n_elements - 1)


@dataclass(frozen=True)
class Matrices:
    """Second-order model M q'' + C q' + K q = F_v v + (extra torques), SI units.

    M, C, K: (n_dof, n_dof); f_v: (n_dof,) generalized force per DAC count.
    c_drive, k_drive: the drive train's part of C and K (so it can be switched off).
    """

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    f_v: np.ndarray
    c_drive: np.ndarray
    k_drive: np.ndarray
    n_elements: int


def _beam_element(mu: float, EI: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Hermite cubic element, DOFs [w1, phi1, w2, phi2]: consistent mass and stiffness."""
    m = mu * h / 420.0 * np.array([[156, 22 * h, 54, -13 * h],
                                   [22 * h, 4 * h * h, 13 * h, -3 * h * h],
                                   [54, 13 * h, 156, -22 * h],
                                   [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    k = EI / h**3 * np.array([[12, 6 * h, -12, 6 * h],
                              [6 * h, 4 * h * h, -6 * h, 2 * h * h],
                              [-12, -6 * h, 12, -6 * h],
                              [6 * h, 2 * h * h, -6 * h, 4 * h * h]])
    return m, k


def motor_inertia(p: Params) -> tuple[float, float]:
    """(J_m, c_m): motor angle/v = num/(s(s+act_p)), num = act_K*|2*pi*j + act_p|."""
    num = p.act_K * abs(complex(p.act_p, 2 * math.pi))
    j_m = K_TAU / num
    return j_m, p.act_p * j_m


def assemble(p: Params, n_elements: int = 4, beta: float = 0.0) -> Matrices:
    """Assemble the plant.

    Parameters
    ----------
    p : Params
    n_elements : int
        Beam elements (>= 1).
    beta : float
        Stiffness-proportional damping of the beam elements, s (C_beam = beta*K_beam).
    """
    n = 3 + 2 * n_elements
    M, C, K = (np.zeros((n, n)) for _ in range(3))
    j_m, c_m = motor_inertia(p)
    M[MOTOR, MOTOR] += j_m
    C[MOTOR, MOTOR] += c_m
    M[BASE, BASE] += p.J_base
    pair = np.array([[1.0, -1.0], [-1.0, 1.0]])
    kd, cd = np.zeros((n, n)), np.zeros((n, n))
    kd[np.ix_([MOTOR, BASE], [MOTOR, BASE])] = p.drive_k * pair
    cd[np.ix_([MOTOR, BASE], [MOTOR, BASE])] = p.drive_c * pair
    K += kd
    C += cd
    K[np.ix_([BASE, ROOT], [BASE, ROOT])] += p.clamp_k * pair
    C[np.ix_([BASE, ROOT], [BASE, ROOT])] += p.clamp_c * pair
    me, ke = _beam_element(p.mu, p.EI, p.L / n_elements)
    for e in range(n_elements):
        # node e: (w, phi); node 0's w is pinned (dropped), its phi is the root slope
        left = [None, ROOT] if e == 0 else [3 + 2 * (e - 1), 4 + 2 * (e - 1)]
        dofs = left + [3 + 2 * e, 4 + 2 * e]
        keep = [i for i, d in enumerate(dofs) if d is not None]
        idx = [dofs[i] for i in keep]
        M[np.ix_(idx, idx)] += me[np.ix_(keep, keep)]
        K[np.ix_(idx, idx)] += ke[np.ix_(keep, keep)]
        C[np.ix_(idx, idx)] += beta * ke[np.ix_(keep, keep)]
    tip = tip_w(n_elements)
    M[tip, tip] += p.m_accel
    M[tip + 1, tip + 1] += p.J_accel
    f_v = np.zeros(n)
    f_v[MOTOR] = K_TAU
    return Matrices(M, C, K, f_v, cd, kd, n_elements)


def held_first_mode(p: Params, n_elements: int = 4, beta: float = 0.0) -> tuple[float, float]:
    """First beam mode with motor and base held still: (frequency Hz, damping ratio)."""
    m = assemble(p, n_elements, beta)
    free = slice(ROOT, None)
    M, C, K = m.M[free, free], m.C[free, free], m.K[free, free]
    nd = M.shape[0]
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((nd, nd)), np.eye(nd)], [-Minv @ K, -Minv @ C]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 1e-9]
    # the lowest undamped frequency |lambda| among the oscillatory pairs
    first = lam[np.argmin(np.abs(lam))]
    return abs(first) / (2 * math.pi), -first.real / abs(first)


def beta_for_damping(p: Params, zeta: float, n_elements: int = 4) -> float:
    """The beam's stiffness-proportional damping beta (s) giving the first held mode the
    total damping ratio ``zeta``; 0 when the set's own damping is already >= zeta."""
    own = held_first_mode(p, n_elements, 0.0)[1]
    if zeta <= own:
        return 0.0
    f = lambda b: held_first_mode(p, n_elements, b)[1] - zeta  # noqa: E731
    hi = 2 * (zeta - own) / (2 * math.pi * held_first_mode(p, n_elements, 0.0)[0]) * 4 + 1e-6
    while f(hi) < 0:
        hi *= 2
    return brentq(f, 0.0, hi, xtol=1e-12, rtol=1e-10)
