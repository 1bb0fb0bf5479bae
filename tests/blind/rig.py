"""The rig for the blind generator: compensators, timing, amplifier, plant and sensors.

From DESIGN.md alone ("Compensators", "Timing and log rows", "Model diagnosis contract"):

- alignment 1: v[k] = C(u[k], theta[k-1], a[k-1]), v[0] = 0 (open loop: v[k] = u[k]);
- the PC truncates v toward zero, then the amplifier: saturation, dead-zone, extra delay
  (that order); the torque on the motor is k_tau times the result;
- the plant is integrated on a sub-step grid (``substeps`` per sample, exact ZOH of its
  linear part per sub-step) when Coulomb friction (stick-slip) or backlash act, with the
  friction torque and the backlash's spring offset held over each sub-step and the motor
  held (exact) while it sticks; without them one exact ZOH step per sample is the same;
- theta = H * base angle rounded to whole counts; a = a_gain * tip lateral acceleration
  + Gaussian noise (0.3 counts std), rounded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import expm
from scipy.signal import bilinear

from tests.blind.fem import BASE, H, K_TAU, MOTOR, Params, assemble, beta_for_damping, tip_w

DT = 0.002
"""Sample time, s."""

LIMIT = 200.0
"""The rig software's clamp of v, DAC counts."""

ACCEL_NOISE = 0.3
"""Accelerometer noise std, counts."""

NAMED = ("coulomb_friction", "deadzone", "saturation", "delay", "backlash", "beam_damping", "accel_gain")
"""The named effects of the vocabulary (besides param:NAME)."""


# --- compensators ------------------------------------------------------------------------

def tustin(num_s, den_s, dt: float = DT) -> tuple[np.ndarray, np.ndarray]:
    """Tustin (bilinear) discretization, coefficients in powers of z^-1, den[0] = 1."""
    b, a = bilinear(num_s, den_s, fs=1.0 / dt)
    return np.asarray(b, float) / a[0], np.asarray(a, float) / a[0]


def gth_design(dt: float = DT) -> tuple[np.ndarray, np.ndarray]:
    """Lead Gth(s) = 5 (p/z)(s+z)/(s+p), p = 2 pi 20, z = 2 pi 5, Tustin at dt."""
    p, z = 2 * math.pi * 20, 2 * math.pi * 5
    return tustin([5 * p / z, 5 * p], [1.0, p], dt)


def ga_design(dt: float = DT) -> tuple[np.ndarray, np.ndarray]:
    """Accelerometer Ga(s) = (b1 s + b0)/(s^3 + a2 s^2 + a1 s + a0), Tustin at dt."""
    a2, a1, a0, b1, b0 = 36.49022971, 172.1552844, 15.39673089, 467.22634242, 281.56096177
    return tustin([b1, b0], [1.0, a2, a1, a0], dt)


class Filter:
    """Direct-form discrete TF; the output history is what was actually used (anti-windup)."""

    def __init__(self, num, den, limit: float = math.inf):
        self.b, self.a, self.limit = list(num), list(den), limit
        self.x = [0.0] * len(self.b)
        self.y = [0.0] * len(self.a)

    def step(self, x: float) -> float:
        self.x = [x] + self.x[:-1]
        acc = sum(bi * xi for bi, xi in zip(self.b, self.x))
        acc -= sum(ai * yi for ai, yi in zip(self.a[1:], self.y[:-1]))
        y = min(max(acc, -self.limit), self.limit)
        self.y = [y] + self.y[:-1]
        return y


class Controller:
    """P (kp) or lead Gth, optionally with accelerometer feedback Ga:
    theta_d_hat = u - Ga(a); e = theta_d_hat - theta; v = sat(Gth(e)) at +-LIMIT."""

    def __init__(self, kind: str, kp: float = 2.0):
        self.kind = kind
        self.gth = Filter([kp], [1.0], LIMIT) if kind == "p" else Filter(*gth_design(), LIMIT)
        self.ga = Filter(*ga_design()) if kind == "lead-accel" else None

    def step(self, u: float, theta: float, a: float) -> tuple[float, float]:
        th_d = u - (self.ga.step(a) if self.ga is not None else 0.0)
        return self.gth.step(th_d - theta), th_d


# --- amplifier ---------------------------------------------------------------------------

class Amplifier:
    """The PC's truncation toward zero, then saturation, dead-zone and extra delay."""

    def __init__(self, saturation: float = math.inf, deadzone: float = 0.0, delay: int = 0):
        self.sat, self.w = saturation, deadzone
        self.buf = [0.0] * int(delay)

    def __call__(self, v: float) -> float:
        v = float(math.trunc(v))
        v = min(max(v, -self.sat), self.sat)
        v = 0.0 if abs(v) <= self.w else v - math.copysign(self.w, v)
        if not self.buf:
            return v
        self.buf.append(v)
        return self.buf.pop(0)


# --- plant -------------------------------------------------------------------------------

def _zoh(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    n, m = B.shape
    big = np.zeros((n + m, n + m))
    big[:n, :n], big[:n, n:] = A, B
    e = expm(big * h)
    return e[:n, :n], e[:n, n:]


class Plant:
    """The FEM plant with Coulomb friction (stick-slip) on the motor and backlash in the
    drive train, stepped one sample at a time with the torque command held (ZOH).

    Parameters
    ----------
    params : Params
    n_elements : int
    beta : float
        Stiffness-proportional beam damping, s.
    friction : float
        Coulomb friction level v_c, DAC counts (torque k_tau*v_c; static = kinetic).
    backlash : float
        Total free play of the drive train, encoder counts.
    substeps : int
        Sub-steps per sample when friction or backlash act.
    """

    def __init__(self, params: Params, n_elements: int = 4, beta: float = 0.0, friction: float = 0.0,
                 backlash: float = 0.0, substeps: int = 100, dt: float = DT):
        m = assemble(params, n_elements, beta)
        self.nd = nd = m.M.shape[0]
        self.kd, self.cd = params.drive_k, params.drive_c
        self.fc = K_TAU * friction
        self.g2 = 0.5 * backlash / H
        self.nonlinear = friction > 0 or backlash > 0
        minv = np.linalg.inv(m.M)
        inputs = np.zeros((nd, 3))
        inputs[:, 0] = m.f_v
        inputs[MOTOR, 1] = 1.0
        inputs[BASE, 2] = 1.0

        def state_space(K, C):
            A = np.block([[np.zeros((nd, nd)), np.eye(nd)], [-minv @ K, -minv @ C]])
            return A, np.vstack([np.zeros((nd, 3)), minv @ inputs])

        A, B = state_space(m.K, m.C)
        self.accel_row = A[nd + tip_w(n_elements)].copy()  # tip acceleration (D = 0: torque is on the motor)
        if not self.nonlinear:
            self.steps = 1
            self.phi, self.gam = _zoh(A, B[:, :1], dt)
            self.gam = self.gam[:, 0]
        else:
            self.steps = int(substeps)
            h = dt / self.steps
            variants = {}
            for coupled in (True, False):
                Av, Bv = state_space(m.K, m.C) if coupled else state_space(m.K - m.k_drive, m.C - m.c_drive)
                for stuck in (False, True):
                    As, Bs = Av.copy(), Bv.copy()
                    if stuck:  # motor held: its angle and (zero) speed do not change
                        As[[MOTOR, nd + MOTOR]] = 0.0
                        Bs[[MOTOR, nd + MOTOR]] = 0.0
                    variants[coupled, stuck] = _zoh(As, Bs, h)
            self.variants = variants
        self.reset()

    def reset(self) -> None:
        self.x = np.zeros(2 * self.nd)
        self.stuck = self.fc > 0
        self.direction = 0.0

    def outputs(self) -> tuple[float, float]:
        """(base angle * H in counts, tip lateral acceleration m/s^2) at the current state."""
        return H * self.x[BASE], float(self.accel_row @ self.x)

    def advance(self, v: float) -> None:
        """One sample with the torque command v (DAC counts after the amplifier) held."""
        if not self.nonlinear:
            self.x = self.phi @ self.x + self.gam * v
            return
        nd, x = self.nd, self.x
        kd, cd, g2, fc = self.kd, self.cd, self.g2, self.fc
        tau_v = K_TAU * v
        for _ in range(self.steps):
            delta = x[MOTOR] - x[BASE]
            coupled, offset = True, 0.0
            if g2 > 0.0:
                if abs(delta) <= g2:
                    coupled = False
                else:  # engaged: spring acts on (delta -+ gap/2); the linear part has kd*delta
                    offset = kd * math.copysign(g2, delta)
            f_m, f_b = offset, -offset
            if fc > 0.0:
                if self.stuck:
                    # torque on the still motor from the amplifier and the drive train
                    drive = (kd * delta - offset + cd * (0.0 - x[nd + BASE])) if coupled else 0.0
                    net = tau_v - drive
                    if abs(net) > fc:
                        self.stuck = False
                        self.direction = math.copysign(1.0, net)
                if not self.stuck:
                    f_m -= self.direction * fc
            phi, gam = self.variants[coupled, self.stuck]
            x = phi @ x + gam @ np.array((v, f_m, f_b))
            if fc > 0.0 and not self.stuck and x[nd + MOTOR] * self.direction <= 0.0:
                x[nd + MOTOR] = 0.0  # the motor stopped within the sub-step: it sticks
                self.stuck = True
        self.x = x


# --- one run -----------------------------------------------------------------------------

@dataclass
class Run:
    """One simulated run as the rig logs it (arrays of shape (N,))."""

    u: np.ndarray
    v: np.ndarray
    theta: np.ndarray
    a: np.ndarray
    theta_d_hat: np.ndarray
    applied: np.ndarray = field(repr=False)


def split_effects(effects: dict[str, float]) -> tuple[dict[str, float], dict[str, float]]:
    """(named effects, param ratios); ValueError for an unknown name."""
    named, ratios = {}, {}
    for name, value in effects.items():
        if name.startswith("param:"):
            pname = name.split(":", 1)[1]
            if pname not in Params.__dataclass_fields__ or pname in ("L", "a_gain"):
                raise ValueError(f"unknown parameter effect {name!r}")
            ratios[pname] = float(value)
        elif name in NAMED:
            named[name] = float(value)
        else:
            raise ValueError(f"unknown effect {name!r}")
    return named, ratios


def make_plant(effects: dict[str, float], n_elements: int = 4, substeps: int = 100) -> tuple[Plant, float]:
    """The plant with the effects that act inside it, and the accelerometer gain (counts per m/s^2)."""
    named, ratios = split_effects(effects)
    params = Params().scaled(ratios)
    zeta = named.get("beam_damping")
    beta = beta_for_damping(params, zeta, n_elements) if zeta else 0.0
    plant = Plant(params, n_elements, beta, friction=named.get("coulomb_friction", 0.0),
                  backlash=named.get("backlash", 0.0), substeps=substeps)
    return plant, params.a_gain * named.get("accel_gain", 1.0)


def simulate(kind: str, u: np.ndarray, effects: dict[str, float], rng: np.random.Generator,
             n_elements: int = 4, substeps: int = 100, accel_noise: float = ACCEL_NOISE,
             kp: float = 2.0) -> Run:
    """Simulate one run of the rig.

    Parameters
    ----------
    kind : {"p", "lead", "lead-accel", "open-loop"}
    u : array, shape (N,)
        Reference, encoder counts (DAC counts in open loop, v = u).
    effects : dict
        Effect name -> value (DESIGN.md vocabulary and units).
    rng : numpy.random.Generator
        Accelerometer noise.
    """
    named, _ = split_effects(effects)
    plant, a_gain = make_plant(effects, n_elements, substeps)
    amp = Amplifier(named.get("saturation", math.inf), named.get("deadzone", 0.0), int(named.get("delay", 0)))
    ctrl = None if kind == "open-loop" else Controller(kind, kp)
    n = len(u)
    out = np.zeros((6, n))
    noise = rng.normal(0.0, accel_noise, n) if accel_noise > 0 else np.zeros(n)
    for k in range(n):
        th, acc = plant.outputs()
        theta = math.floor(th + 0.5)
        a = math.floor(a_gain * acc + noise[k] + 0.5)
        if ctrl is None:
            v, th_d = float(u[k]), float(u[k])
        elif k == 0:
            v, th_d = 0.0, float(u[0])
        else:  # alignment 1: the previous row's samples
            v, th_d = ctrl.step(float(u[k]), out[2, k - 1], out[3, k - 1])
        applied = amp(v)
        out[:, k] = (u[k], v, theta, a, th_d, applied)
        plant.advance(applied)
    return Run(*out)
