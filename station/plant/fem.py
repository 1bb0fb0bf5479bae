"""FEM model of the SFLR: Hermite cubic Euler–Bernoulli elements, consistent mass.

Thesis chapters III–IV (DESIGN.md "FEM plant"), in SI units with no element-length
scaling of the rotational DOFs. Generalized coordinates of the SFLR model::

    q = [theta_m, theta_b, phi_0, w_1, phi_1, ..., w_n, phi_n]

motor angle, base angle, beam root slope (rad), then the lateral displacement w (m) and
slope phi (rad) of each beam node; the root's lateral displacement is pinned (w_0 = 0).
w is measured in the inertial frame, positive towards increasing theta, so a rigid
rotation by theta gives w(x) = x·theta, phi = theta.
"""

from __future__ import annotations

import numpy as np

# scipy.linalg / scipy.signal / scipy.optimize / python-control are imported where used:
# they cost seconds, and a run's first tick does not need them (start-up time).

from station.plant.parameters import Params, load_params

N_ELEMENTS_MAX = 100
"""Largest supported element count."""

BOUNDARY_CONDITIONS = ("pinned-free", "cantilever", "free-free")


def element_matrices(EI: float, mu: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass matrices of one Hermite cubic beam element.

    Parameters
    ----------
    EI : float
        Flexural rigidity, N·m².
    mu : float
        Mass per length, kg/m.
    h : float
        Element length, m.

    Returns
    -------
    K, M : ndarray, shape (4, 4)
        Over the element DOFs [w_i, phi_i, w_i+1, phi_i+1] (m, rad, m, rad);
        K in N/m, N, N·m (per the DOF pair), M in kg, kg·m, kg·m².
        Standard Euler–Bernoulli element (thesis ch. III).
    """
    K = (EI / h**3) * np.array(
        [
            [12.0, 6 * h, -12.0, 6 * h],
            [6 * h, 4 * h**2, -6 * h, 2 * h**2],
            [-12.0, -6 * h, 12.0, -6 * h],
            [6 * h, 2 * h**2, -6 * h, 4 * h**2],
        ]
    )
    M = (mu * h / 420.0) * np.array(
        [
            [156.0, 22 * h, 54.0, -13 * h],
            [22 * h, 4 * h**2, 13 * h, -3 * h**2],
            [54.0, 13 * h, 156.0, -22 * h],
            [-13 * h, -3 * h**2, -22 * h, 4 * h**2],
        ]
    )
    return K, M


def _check_n(n_elements: int) -> int:
    if isinstance(n_elements, bool) or int(n_elements) != n_elements or not 1 <= n_elements <= N_ELEMENTS_MAX:
        raise ValueError(f"n_elements must be an integer in 1..{N_ELEMENTS_MAX}, got {n_elements!r}")
    return int(n_elements)


def assemble_beam(n_elements: int, EI: float, mu: float, L: float) -> tuple[np.ndarray, np.ndarray]:
    """Free-free stiffness and consistent mass matrices of a uniform beam.

    Parameters
    ----------
    n_elements : int
        Number of equal Hermite cubic elements, 1..100.
    EI, mu, L : float
        Flexural rigidity N·m², mass per length kg/m, length m.

    Returns
    -------
    K, M : ndarray, shape (2 n + 2, 2 n + 2)
        Over [w_0, phi_0, w_1, phi_1, ..., w_n, phi_n] (node 0 at the root).
    """
    n = _check_n(n_elements)
    Ke, Me = element_matrices(EI, mu, L / n)
    size = 2 * n + 2
    K = np.zeros((size, size))
    M = np.zeros((size, size))
    for e in range(n):
        s = slice(2 * e, 2 * e + 4)
        K[s, s] += Ke
        M[s, s] += Me
    return K, M


def _beam_free_dofs(n: int, bc: str) -> np.ndarray:
    if bc == "pinned-free":
        return np.arange(1, 2 * n + 2)
    if bc == "cantilever":
        return np.arange(2, 2 * n + 2)
    if bc == "free-free":
        return np.arange(0, 2 * n + 2)
    raise ValueError(f"bc must be one of {BOUNDARY_CONDITIONS}, got {bc!r}")


def beam_modes(
    n_elements: int, bc: str = "pinned-free", EI: float = 1.0, mu: float = 1.0, L: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Elastic natural frequencies and mode shapes of a uniform beam alone.

    Generalized symmetric eigenproblem K φ = ω² M φ (scipy.linalg.eigh) of the
    assembled Hermite cubic model; the rigid-body modes of the boundary condition
    (one for pinned-free, two for free-free) are dropped.

    Parameters
    ----------
    n_elements : int
        Element count, 1..100.
    bc : {"pinned-free", "cantilever", "free-free"}
        Boundary condition at the root (x = 0); the tip is free.
    EI, mu, L : float
        Flexural rigidity N·m², mass per length kg/m, length m.

    Returns
    -------
    omega : ndarray, shape (m,)
        Natural frequencies, rad/s, ascending.
    x : ndarray, shape (n + 1,)
        Node positions, m.
    w : ndarray, shape (n + 1, m)
        Lateral displacement of each mode at the nodes (0 where pinned/clamped),
        each column scaled to unit maximum magnitude, sign such that the tip is >= 0.

    Raises
    ------
    ValueError
        Unknown bc or element count out of range.
    """
    n = _check_n(n_elements)
    K, M = assemble_beam(n, EI, mu, L)
    free = _beam_free_dofs(n, bc)
    import scipy.linalg  # lazy: start-up time (scipy.linalg)
    lam, vec = scipy.linalg.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)])
    rigid = {"pinned-free": 1, "cantilever": 0, "free-free": 2}[bc]
    lam, vec = lam[rigid:], vec[:, rigid:]
    full = np.zeros((2 * n + 2, vec.shape[1]))
    full[free] = vec
    w = full[0::2]
    w = w / np.abs(w).max(axis=0)
    w = w * np.where(w[-1] < 0, -1.0, 1.0)
    return np.sqrt(lam), np.linspace(0.0, L, n + 1), w


def beam_frequencies(
    n_elements: int, bc: str = "pinned-free", EI: float = 1.0, mu: float = 1.0, L: float = 1.0
) -> np.ndarray:
    """Elastic natural frequencies (rad/s, ascending) of a uniform beam alone.

    The first output of `beam_modes`; thesis Table 3.1 lists the pinned-free case
    with EI = mu = L = 1.

    Parameters
    ----------
    n_elements : int
        Element count, 1..100.
    bc : {"pinned-free", "cantilever", "free-free"}, default "pinned-free"
        Boundary condition at the root (x = 0); the tip is free.
    EI, mu, L : float, default 1.0
        Flexural rigidity N·m², mass per length kg/m, length m.
    """
    return beam_modes(n_elements, bc, EI, mu, L)[0]


class SecondOrderModel:
    """M q'' + C q' + K q = b v of the SFLR, SI units (see module docstring for q).

    Parameters
    ----------
    params : Params
        The physical parameters (SI).
    n_elements : int, default 4
        Beam elements, 1..100.

    Attributes
    ----------
    M, C, K : ndarray, shape (n_dof, n_dof)
        Mass kg(·m²), damping and stiffness matrices; n_dof = 2 n + 3.
    b : ndarray, shape (n_dof,)
        Generalized force per DAC count: k_tau on the motor DOF, N·m/count.
    base, root, tip_w : int
        Indices of the base angle, of the beam's root slope (the clamp spring joins
        these two) and of the tip's lateral displacement.
    """

    def __init__(self, params: Params, n_elements: int = 4):
        n = _check_n(n_elements)
        p = params
        Kb, Mb = assemble_beam(n, p.EI, p.mu, p.L)
        beam = np.arange(1, 2 * n + 2)  # drop w_0 (pinned root)
        Kb, Mb = Kb[np.ix_(beam, beam)], Mb[np.ix_(beam, beam)]
        n_dof = 2 + beam.size
        self.n_elements = n
        self.base, self.root, self.tip_w = 1, 2, n_dof - 2
        tip_phi = n_dof - 1
        M = np.zeros((n_dof, n_dof))
        K = np.zeros((n_dof, n_dof))
        C = np.zeros((n_dof, n_dof))
        M[0, 0] = p.J_m
        M[1, 1] = p.J_base
        M[2:, 2:] = Mb
        M[self.tip_w, self.tip_w] += p.m_accel
        M[tip_phi, tip_phi] += p.J_accel
        K[2:, 2:] = Kb
        C[2:, 2:] = p.beam_beta * Kb
        C[0, 0] += p.c_m
        for i, j, k, c in ((0, self.base, p.drive_k, p.drive_c), (self.base, self.root, p.clamp_k, p.clamp_c)):
            spring = np.array([[1.0, -1.0], [-1.0, 1.0]])
            K[np.ix_([i, j], [i, j])] += k * spring
            C[np.ix_([i, j], [i, j])] += c * spring
        b = np.zeros(n_dof)
        b[0] = p.k_tau
        self.M, self.C, self.K, self.b = M, C, K, b


def modal_basis(params: Params, n_elements: int = 4) -> tuple[SecondOrderModel, np.ndarray, np.ndarray, np.ndarray]:
    """The undamped modes under `state_matrices`' state x = [S η, η'], q = Φ η.

    Parameters
    ----------
    params : Params
        The physical parameters (SI).
    n_elements : int, default 4
        Beam elements, 1..100.

    Returns
    -------
    model : SecondOrderModel
    Phi : ndarray, shape (n_dof, n_dof)
        Mass-normalized mode shapes (scipy.linalg.eigh of K, M), rigid-body mode first.
    omega : ndarray, shape (n_dof,)
        Natural frequencies, rad/s (exactly 0 for the rigid-body mode).
    scale : ndarray, shape (n_dof,)
        S = diag(scale): omega, 1 for the rigid-body mode.
    """
    m = SecondOrderModel(params, n_elements)
    import scipy.linalg  # lazy: start-up time (scipy.linalg)
    w2, Phi = scipy.linalg.eigh(m.K, m.M)
    omega = np.sqrt(np.clip(w2, 0.0, None))
    omega[0] = 0.0  # the single rigid-body mode (K r = 0 up to rounding)
    scale = np.where(omega > 0.0, omega, 1.0)
    return m, Phi, omega, scale


def state_matrices(params: Params, n_elements: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First-order realization x' = A x + B v, y = C x of the SFLR, in scaled modal form.

    The undamped problem K φ = ω² M φ (scipy.linalg.eigh, mass-normalized modes Φ,
    q = Φ η) gives one rigid-body mode (the whole link turning: K r = 0; its ω is set to
    exactly 0) and the elastic modes. The state is x = [S η, η'] with S = diag(ω_i)
    (1 for the rigid mode), so that each undamped mode is the skew block
    [[0, ω], [−ω, 0]]: a nearly normal A whose norm is ω_max, not ω_max², which keeps
    the ZOH matrix exponential and the sampled stepping accurate at 100 elements
    (the physical coordinates [q, q'] have ‖A‖ ≈ 1e15 there). The damping Φᵀ C Φ
    (motor, drive train, clamp, Rayleigh beam damping) couples the modes.

    Parameters
    ----------
    params : Params
        Parameter set (SI).
    n_elements : int
        Beam element count, 1..100.

    Returns
    -------
    A : ndarray, shape (2 n_dof, 2 n_dof)
        n_dof = 2 n + 3; units 1/s.
    B : ndarray, shape (2 n_dof, 1)
        Per DAC count (torque k_tau·v on the motor DOF).
    C : ndarray, shape (2, 2 n_dof)
        Rows: theta = H·theta_b (encoder counts) and a = a_gain·w_tip'' (accelerometer
        counts, positive towards increasing theta). The accelerometer's feed-through
        a_gain·(M⁻¹ b)_tip is zero (the torque acts on the motor only, DESIGN.md), so
        D = 0.
    """
    return realization(params, modal_basis(params, n_elements))


def realization(params: Params, basis: tuple[SecondOrderModel, np.ndarray, np.ndarray, np.ndarray]
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`state_matrices` from a :func:`modal_basis` already at hand (a caller that
    needs the basis too decomposes once).

    Parameters
    ----------
    params : Params
        The parameter set the basis was computed for.
    basis : tuple
        ``modal_basis(params, n_elements)``.

    Returns
    -------
    A, B, C : ndarray
        As :func:`state_matrices`.
    """
    m, Phi, omega, scale = basis
    n_dof = m.M.shape[0]
    damping = Phi.T @ m.C @ Phi
    Z = np.zeros((n_dof, n_dof))
    A = np.block([[Z, np.diag(scale)], [-np.diag(omega**2 / scale), -damping]])
    B = np.concatenate([np.zeros(n_dof), Phi.T @ m.b])[:, None]
    C = np.zeros((2, 2 * n_dof))
    C[0, :n_dof] = params.H * Phi[m.base] / scale
    C[1] = params.a_gain * (Phi[m.tip_w] @ A[n_dof:])
    return A, B, C


def build_continuous(params: Params | None = None, n_elements: int = 4) -> control.StateSpace:
    """Continuous-time state-space model of the SFLR from v to [theta, a].

    Parameters
    ----------
    params : Params, optional
        Parameter set; default ``load_params("tmm-fit")``.
    n_elements : int, default 4
        Beam element count, 1..100.

    Returns
    -------
    control.StateSpace
        Input v (DAC counts); outputs [theta (encoder counts, float), a (accelerometer
        counts, float)]; D = 0; 2·(2 n + 3) states in scaled modal form (see
        `state_matrices`).

    Raises
    ------
    ValueError
        Element count out of range.
    """
    if params is None:
        params = load_params()
    A, B, C = state_matrices(params, n_elements)
    import control  # lazy: start-up time (python-control)
    return control.ss(A, B, C, np.zeros((2, 1)), inputs=["v"], outputs=["theta", "a"])
