"""The rig for the blind generator: compensators, timing, amplifier, plant and sensors.

From DESIGN.md alone ("Compensators", "Timing and log rows", "Model diagnosis contract"):

- alignment 1: v[k] = C(u[k], theta[k-1], a[k-1]), v[0] = 0 (open loop: v[k] = u[k]); the
  log holds this computed v, whatever the amplifier then makes of it; alignment 0 (the rig's
  2009 logs): v[k] = C(u[k], theta[k], a[k]);
- the PC truncates v toward zero, then the amplifier: offset (amp_offset), saturation,
  dead-zone, extra delay (that order); the torque on the motor is k_tau times the result;
- the plant: the FEM with the motor's viscous friction (viscous_friction) added to the
  actuator's own damping and any spring to ground (oov:position_spring) in its linear part;
  when dry friction (coulomb_friction, static_friction with its Stribeck curve), backlash
  or cogging act it is integrated on a sub-step grid (``substeps`` per sample, exact ZOH of
  the linear part per sub-step, the nonlinear torques held over each sub-step, the motor
  held exactly while it sticks, micro-steps where the Stribeck curve is steep: see
  :mod:`tests.blind.substep`); without them one exact ZOH step per sample is the same;
- theta = H * base angle (+ the cyclic error of oov:encoder_cyclic) rounded to whole
  counts; a = a_gain * tip lateral acceleration + Gaussian noise (0.3 counts std), rounded.
- sensor and wiring faults (:data:`SENSOR_FAULTS`): the encoder reads encoder_scale * H *
  base angle (4 for a 4096-count encoder, -1 counting the other way); the accelerometer
  accel_gain (either sign) times its sensitivity, plus accel_offset + accel_drift * t
  (counts, counts/s; t = k * DT from the run's first row) before its rounding; a reversed
  motor (motor_polarity -1) turns the amplifier's whole output around, torque
  -k_tau * amplifier output (dry friction still opposes the motion).

- the accelerometer's configuration (:data:`CONFIGURATIONS`): accel_mounted 0 takes it off the
  beam (no point mass nor rotary inertia at the tip, and a reads no tip: its offset and noise
  only); accel_connected 0 leaves it on the tip unplugged (the mass there, a reads its offset
  and noise only).

Effects beyond DESIGN.md's vocabulary ("oov:" names) let tests check that a diagnosis does
not pass them off as a vocabulary cause; see :data:`OOV`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.linalg import expm
from scipy.signal import bilinear

from tests.blind import substep
from tests.blind.fem import BASE, H, K_TAU, MOTOR, Params, assemble, beta_for_damping, motor_inertia, tip_w

DT = 0.002
"""Sample time, s."""

LIMIT = 200.0
"""The rig software's clamp of v, DAC counts."""

ACCEL_NOISE = 0.3
"""Accelerometer noise std, counts."""

STRIBECK_SPEED = 0.05
"""Default Stribeck speed w_s of static_friction, rad/s of the motor (DESIGN.md)."""

STRIBECK_RESOLUTION = 0.01
"""Micro-steps are short enough that the Stribeck curve's steepest negative damping,
divided by the motor inertia, times the micro-step is at most this."""

NAMED = ("coulomb_friction", "deadzone", "saturation", "delay", "backlash", "beam_damping", "accel_gain",
         "static_friction", "viscous_friction", "amp_offset")
"""The named effects of the vocabulary (besides param:NAME)."""

SENSOR_FAULTS = ("accel_offset", "accel_drift", "encoder_scale", "motor_polarity")
"""DESIGN.md's sensor and wiring faults besides accel_gain (one of :data:`NAMED`, which may be
negative here): accelerometer counts, counts per s, measured/modelled encoder counts, +-1."""

CONFIGURATIONS = ("accel_mounted", "accel_connected")
"""How the accelerometer is set up, 1 (on the tip, read) or 0 (module docstring)."""

SETTINGS = ("stribeck_speed",)
"""Keys that set an effect's shape, not an effect: stribeck_speed (rad/s, default
:data:`STRIBECK_SPEED`) of static_friction."""

OOV = {
    "oov:encoder_cyclic": "encoder counts: amplitude A of a cyclic encoder error, "
                          "theta = round(H*base + A*sin(2*pi*H*base/P)) (the controller sees it too)",
    "oov:encoder_cyclic_period": "encoder counts: its period P (default 128)",
    "oov:cogging": "DAC counts: c, a torque -k_tau*c*sin(N*motor angle) on the motor (detents every 2*pi/N)",
    "oov:cogging_cycles": "1: N, cogging cycles per revolution of the motor angle (default 16)",
    "oov:position_spring": "DAC counts per encoder count: s, a torque -k_tau*s*H*base angle on the base "
                           "(a cable pulling the hub back to where the run started)",
}
"""Effects in no vocabulary (name -> unit: meaning); the ``_period``/``_cycles`` keys are
their settings."""

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

    def __init__(self, kind: str, kp: float = 2.0, dt: float = DT):
        self.kind = kind
        self.gth = Filter([kp], [1.0], LIMIT) if kind == "p" else Filter(*gth_design(dt), LIMIT)
        self.ga = Filter(*ga_design(dt)) if kind == "lead-accel" else None

    def step(self, u: float, theta: float, a: float) -> tuple[float, float]:
        th_d = u - (self.ga.step(a) if self.ga is not None else 0.0)
        return self.gth.step(th_d - theta), th_d


# --- effects -----------------------------------------------------------------------------

@dataclass(frozen=True)
class Effects:
    """A run's effects, parsed and checked; the defaults are the nominal rig.

    Attributes
    ----------
    coulomb_friction, static_friction : float
        v_c and v_s, DAC counts; static_friction 0 means v_s = v_c (plain Coulomb friction).
    stribeck_speed : float
        w_s, rad/s of the motor.
    viscous_friction : float
        b, DAC counts per rad/s of the motor.
    amp_offset, saturation, deadzone : float
        DAC counts.
    delay : int
        Samples.
    backlash : float
        Encoder counts (total free play).
    beam_damping : float
        First held mode's total damping ratio (0: the set's own).
    accel_gain : float
        Measured / modelled accelerometer sensitivity.
    ratios : dict
        param:NAME ratios by parameter name.
    encoder_cyclic, encoder_cyclic_period : float
        oov:encoder_cyclic amplitude and period, encoder counts.
    cogging, cogging_cycles : float
        oov:cogging amplitude (DAC counts) and cycles per motor revolution.
    position_spring : float
        oov:position_spring, DAC counts per encoder count.
    accel_offset, accel_drift : float
        Accelerometer bias, counts, and its growth, counts per s from the run's first row.
    encoder_scale : float
        Measured / modelled encoder counts (either sign, not 0).
    motor_polarity : float
        +1, or -1 for a motor the amplifier drives the other way.
    accel_mounted, accel_connected : float
        1, or 0: the accelerometer off the beam / on it unplugged (:data:`CONFIGURATIONS`).
    """

    coulomb_friction: float = 0.0
    static_friction: float = 0.0
    stribeck_speed: float = STRIBECK_SPEED
    viscous_friction: float = 0.0
    amp_offset: float = 0.0
    saturation: float = math.inf
    deadzone: float = 0.0
    delay: int = 0
    backlash: float = 0.0
    beam_damping: float = 0.0
    accel_gain: float = 1.0
    ratios: dict = field(default_factory=dict)
    encoder_cyclic: float = 0.0
    encoder_cyclic_period: float = 128.0
    cogging: float = 0.0
    cogging_cycles: float = 16.0
    position_spring: float = 0.0
    accel_offset: float = 0.0
    accel_drift: float = 0.0
    encoder_scale: float = 1.0
    motor_polarity: float = 1.0
    accel_mounted: float = 1.0
    accel_connected: float = 1.0

    @property
    def accel_reads(self) -> bool:
        """The accelerometer reads the tip: on the beam and plugged in."""
        return bool(self.accel_mounted and self.accel_connected)

    @classmethod
    def parse(cls, effects: dict[str, float]) -> Effects:
        """From effect names (DESIGN.md vocabulary, :data:`SETTINGS`, :data:`OOV`) to values.

        Raises
        ------
        ValueError
            An unknown name, static_friction below coulomb_friction, a stribeck_speed,
            period or cycle count that is not positive.
        """
        fields, ratios = {}, {}
        for name, value in effects.items():
            if name.startswith("param:"):
                pname = name.split(":", 1)[1]
                if pname not in Params.__dataclass_fields__ or pname in ("L", "a_gain"):
                    raise ValueError(f"unknown parameter effect {name!r}")
                ratios[pname] = float(value)
            elif name in NAMED or name in SETTINGS or name in SENSOR_FAULTS or name in CONFIGURATIONS:
                fields[name] = int(value) if name == "delay" else float(value)
            elif name in OOV:
                fields[name.split(":", 1)[1]] = float(value)
            else:
                raise ValueError(f"unknown effect {name!r}")
        eff = cls(ratios=ratios, **fields)
        if eff.static_friction and eff.static_friction < eff.coulomb_friction:
            raise ValueError(f"static_friction {eff.static_friction:g} below coulomb_friction "
                             f"{eff.coulomb_friction:g} (the breakaway level is v_s >= v_c)")
        if min(eff.stribeck_speed, eff.encoder_cyclic_period, eff.cogging_cycles) <= 0:
            raise ValueError("stribeck_speed, oov:encoder_cyclic_period and oov:cogging_cycles must be positive")
        if eff.motor_polarity not in (1.0, -1.0) or eff.encoder_scale == 0 or eff.accel_gain == 0:
            raise ValueError("motor_polarity must be +1 or -1, encoder_scale and accel_gain not 0")
        if eff.accel_mounted not in (0.0, 1.0) or eff.accel_connected not in (0.0, 1.0):
            raise ValueError("accel_mounted and accel_connected must be 0 or 1")
        return eff

    @property
    def breakaway(self) -> float:
        """v_s, DAC counts: static_friction, or coulomb_friction when that is not given."""
        return max(self.static_friction, self.coulomb_friction)


# --- amplifier ---------------------------------------------------------------------------

class Amplifier:
    """The PC's truncation toward zero, then the amplifier's offset, saturation, dead-zone
    and extra delay (DESIGN.md's order)."""

    def __init__(self, saturation: float = math.inf, deadzone: float = 0.0, delay: int = 0, offset: float = 0.0):
        self.sat, self.w, self.offset = saturation, deadzone, offset
        self.buf = [self._shape(0.0)] * int(delay)  # before the run the PC sent 0

    def _shape(self, v: float) -> float:
        v = float(math.trunc(v)) + self.offset
        v = min(max(v, -self.sat), self.sat)
        return 0.0 if abs(v) <= self.w else v - math.copysign(self.w, v)

    def __call__(self, v: float) -> float:
        v = self._shape(v)
        if not self.buf:
            return v
        self.buf.append(v)
        return self.buf.pop(0)


# --- sensors -----------------------------------------------------------------------------

def encoder(counts: float, cyclic: float = 0.0, period: float = 128.0) -> float:
    """The encoder's reading of a base angle of ``counts`` (H * rad): with a cyclic error of
    amplitude ``cyclic`` and ``period`` (encoder counts), rounded to the nearest count."""
    if cyclic:
        counts += cyclic * math.sin(2 * math.pi * counts / period)
    return float(math.floor(counts + 0.5))


def accel_bias(eff: Effects, k: int) -> float:
    """The accelerometer's offset and drift at row k of a run, counts (0 without them)."""
    return eff.accel_offset + eff.accel_drift * k * DT


# --- plant -------------------------------------------------------------------------------

def _zoh(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    n, m = B.shape
    big = np.zeros((n + m, n + m))
    big[:n, :n], big[:n, n:] = A, B
    e = expm(big * h)
    return e[:n, :n], e[:n, n:]


@functools.lru_cache(maxsize=16)
def _matrices(params: Params, n_elements: int, beta: float, viscous: float, ground_spring: float, dt: float,
              steps: int, micro: int):
    """(n_dof, tip acceleration row, phi, gam, micro phi, micro gam) of a plant, cached: the
    runs of a case share them. ``steps`` = 0: one exact ZOH step of the linear plant per
    sample (phi (2n, 2n), gam (2n,)); else the four sub-step variants (index 2*coupled +
    stuck) with inputs (v, motor torque, base torque), and those of a micro-step."""
    m = assemble(params, n_elements, beta)
    nd = m.M.shape[0]
    K, C = m.K.copy(), m.C.copy()
    C[MOTOR, MOTOR] += K_TAU * viscous  # linear: exact in the ZOH matrices
    K[BASE, BASE] += K_TAU * ground_spring * H
    minv = np.linalg.inv(m.M)
    inputs = np.zeros((nd, 3))
    inputs[:, 0] = m.f_v
    inputs[MOTOR, 1] = 1.0
    inputs[BASE, 2] = 1.0

    def state_space(K, C):
        A = np.block([[np.zeros((nd, nd)), np.eye(nd)], [-minv @ K, -minv @ C]])
        return A, np.vstack([np.zeros((nd, 3)), minv @ inputs])

    A, B = state_space(K, C)
    accel_row = A[nd + tip_w(n_elements)].copy()  # tip acceleration (D = 0: torque is on the motor)
    if not steps:
        phi, gam = _zoh(A, B[:, :1], dt)
        out = (accel_row, phi, gam[:, 0], None, None)
    else:
        models = {coupled: state_space(K, C) if coupled else state_space(K - m.k_drive, C - m.c_drive)
                  for coupled in (False, True)}

        def variants(h):
            phis, gams = [], []
            for coupled in (False, True):
                for stuck in (False, True):
                    As, Bs = (a.copy() for a in models[coupled])
                    if stuck:  # motor held: its angle and (zero) speed do not change
                        As[[MOTOR, nd + MOTOR]] = 0.0
                        Bs[[MOTOR, nd + MOTOR]] = 0.0
                    phi, gam = _zoh(As, Bs, h)
                    phis.append(phi)
                    gams.append(gam)
            return np.ascontiguousarray(phis), np.ascontiguousarray(gams)

        phi, gam = variants(dt / steps)
        fphi, fgam = variants(dt / steps / micro) if micro > 1 else (phi, gam)
        out = (accel_row, phi, gam, fphi, fgam)
    for a in out:
        if a is not None:
            a.flags.writeable = False
    return (nd, *out)


class Plant:
    """The FEM plant with the motor's friction and cogging and the drive train's backlash,
    stepped one sample at a time with the torque command held (ZOH).

    Parameters
    ----------
    params : Params
    n_elements : int
    beta : float
        Stiffness-proportional beam damping, s.
    friction : float
        Coulomb (sliding) friction level v_c, DAC counts.
    backlash : float
        Total free play of the drive train, encoder counts.
    substeps : int
        Sub-steps per sample when friction, backlash or cogging act.
    dt : float
        Sample time, s.
    static_friction : float
        Breakaway level v_s >= v_c, DAC counts (0: v_s = v_c).
    stribeck_speed : float
        w_s of the Stribeck curve, rad/s of the motor.
    viscous : float
        Viscous friction b, DAC counts per rad/s of the motor (torque k_tau*b*w).
    cogging, cogging_cycles : float
        Cogging torque -k_tau*cogging*sin(cogging_cycles*motor angle).
    ground_spring : float
        A spring from the base to the ground, DAC counts per encoder count
        (torque -k_tau*ground_spring*H*base angle).
    """

    def __init__(self, params: Params, n_elements: int = 4, beta: float = 0.0, friction: float = 0.0,
                 backlash: float = 0.0, substeps: int = 100, dt: float = DT, *, static_friction: float = 0.0,
                 stribeck_speed: float = STRIBECK_SPEED, viscous: float = 0.0, cogging: float = 0.0,
                 cogging_cycles: float = 16.0, ground_spring: float = 0.0):
        v_s = max(static_friction, friction)
        self.cfg = substep.config(params.drive_k, params.drive_c, 0.5 * backlash / H, K_TAU * friction,
                                  K_TAU * v_s, stribeck_speed, K_TAU * cogging, cogging_cycles, K_TAU)
        self.nonlinear = v_s > 0 or backlash > 0 or cogging != 0
        self.steps = int(substeps) if self.nonlinear else 1
        self.micro = 1
        if self.nonlinear and v_s > friction:
            # the Stribeck curve's steepest slope, k_tau (v_s - v_c) sqrt(2) e^-1/2 / w_s, over J_m
            rate = K_TAU * (v_s - friction) * math.sqrt(2) * math.exp(-0.5) / stribeck_speed
            rate /= motor_inertia(params)[0]
            self.micro = max(2, math.ceil(rate * dt / self.steps / STRIBECK_RESOLUTION))
        self.band = substep.BAND * stribeck_speed
        self.nd, self.accel_row, self.phi, self.gam, self.fphi, self.fgam = _matrices(
            params, n_elements, beta, viscous, ground_spring, dt, self.steps if self.nonlinear else 0, self.micro)
        self.reset()

    def reset(self) -> None:
        """At rest at the origin; the motor stuck when there is dry friction."""
        self.x = np.zeros(2 * self.nd)
        self.st = np.array([1.0 if self.cfg[substep.FS] > 0 else 0.0, 0.0])

    @property
    def stuck(self) -> bool:
        """The motor is held by dry friction."""
        return bool(self.st[0])

    def outputs(self) -> tuple[float, float]:
        """(base angle * H in counts, tip lateral acceleration m/s^2) at the current state."""
        return H * self.x[BASE], float(self.accel_row @ self.x)

    def motor(self) -> float:
        """Motor angle * H, counts."""
        return H * self.x[MOTOR]

    def advance(self, v: float) -> None:
        """One sample with the torque command v (DAC counts after the amplifier) held."""
        if not self.nonlinear:
            self.x = self.phi @ self.x + self.gam * v
            return
        self.x = substep.advance(self.x, float(v), self.st, self.phi, self.gam, self.fphi, self.fgam, self.cfg,
                                 self.nd, self.steps, self.micro, self.band)


# --- one run -----------------------------------------------------------------------------

@dataclass
class Run:
    """One simulated run as the rig logs it (arrays of shape (N,)), and what it hides.

    ``applied`` is the amplifier's output (DAC counts) during tick k; ``theta_true`` the
    base angle and ``motor`` the motor angle at tick k, in encoder counts before the
    encoder's error and rounding.
    """

    u: np.ndarray
    v: np.ndarray
    theta: np.ndarray
    a: np.ndarray
    theta_d_hat: np.ndarray
    applied: np.ndarray = field(repr=False)
    theta_true: np.ndarray = field(repr=False)
    motor: np.ndarray = field(repr=False)


def make_plant(effects: dict[str, float] | Effects, n_elements: int = 4, substeps: int = 100,
               dt: float = DT) -> tuple[Plant, float]:
    """The plant with the effects that act inside it, and the accelerometer gain (counts per m/s^2)."""
    eff = effects if isinstance(effects, Effects) else Effects.parse(effects)
    params = Params().scaled(eff.ratios)
    if not eff.accel_mounted:  # the accelerometer off the beam: nothing at the tip
        params = replace(params, m_accel=0.0, J_accel=0.0)
    beta = beta_for_damping(params, eff.beam_damping, n_elements) if eff.beam_damping else 0.0
    plant = Plant(params, n_elements, beta, friction=eff.coulomb_friction, backlash=eff.backlash,
                  substeps=substeps, static_friction=eff.static_friction, stribeck_speed=eff.stribeck_speed,
                  viscous=eff.viscous_friction, cogging=eff.cogging, cogging_cycles=eff.cogging_cycles,
                  ground_spring=eff.position_spring, dt=dt)
    return plant, params.a_gain * eff.accel_gain


def simulate(kind: str, u: np.ndarray, effects: dict[str, float], rng: np.random.Generator,
             n_elements: int = 4, substeps: int = 100, accel_noise: float = ACCEL_NOISE,
             kp: float = 2.0, alignment: int = 1, dt: float = DT) -> Run:
    """Simulate one run of the rig.

    Parameters
    ----------
    kind : {"p", "lead", "lead-accel", "open-loop"}
    u : array, shape (N,)
        Reference, encoder counts (DAC counts in open loop, v = u).
    effects : dict
        Effect name -> value (DESIGN.md vocabulary and units, :data:`SETTINGS`, :data:`OOV`).
    rng : numpy.random.Generator
        Accelerometer noise.
    n_elements : int
        Beam elements.
    substeps : int
        Sub-steps per sample for friction, backlash and cogging.
    accel_noise : float
        Accelerometer noise std, counts.
    kp : float
        Gain of the P controller.
    alignment : {1, 0}
        1: the command of row k from row k-1's samples (v[0] = 0); 0: from row k's own.
    dt : float
        Sample time, s: the loop's and the plant's (a rig run at another rate than 500 Hz; the
        lead and Ga by Tustin at it).
    """
    if alignment not in (0, 1):
        raise ValueError(f"alignment {alignment!r}: expected 0 or 1")
    eff = Effects.parse(effects)
    plant, a_gain = make_plant(eff, n_elements, substeps, dt)
    amp = Amplifier(eff.saturation, eff.deadzone, eff.delay, eff.amp_offset)
    ctrl = None if kind == "open-loop" else Controller(kind, kp, dt)
    n = len(u)
    out = np.zeros((8, n))
    noise = rng.normal(0.0, accel_noise, n) if accel_noise > 0 else np.zeros(n)
    for k in range(n):
        th, acc = plant.outputs()
        theta = encoder(eff.encoder_scale * th, eff.encoder_cyclic, eff.encoder_cyclic_period)
        tip = a_gain * acc if eff.accel_reads else 0.0  # a dead channel reads its bias and noise
        a = math.floor(tip + accel_bias(eff, k) + noise[k] + 0.5)
        if ctrl is None:
            v, th_d = float(u[k]), float(u[k])
        elif alignment == 0:  # the 2009 logs: this row's samples
            v, th_d = ctrl.step(float(u[k]), float(theta), float(a))
        elif k == 0:
            v, th_d = 0.0, float(u[0])
        else:  # alignment 1: the previous row's samples
            v, th_d = ctrl.step(float(u[k]), out[2, k - 1], out[3, k - 1])
        applied = amp(v)
        out[:, k] = (u[k], v, theta, a, th_d, applied, th, plant.motor())
        plant.advance(eff.motor_polarity * applied)
    return Run(*out)
