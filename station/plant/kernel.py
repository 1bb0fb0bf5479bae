"""The compiled sample loop of the SFLR simulation and the per-sample functions it shares.

The plant is stepped in its modal form (:mod:`station.plant.modal`): z_{k+1} = Λ z_k +
b_m v[k], y_k = Re(C_m z_k). :func:`run_kernel` is a whole run's sample loop, with the
compensator's recursions, clamp, sensor and command quantization (:mod:`station.rounding`)
and a model's effects, compiled by numba (without numba the same code runs as plain
Python, same results, about 1000x slower). :class:`Stepper` / :class:`ModelPlant` step
the same compiled functions one sample at a time (the simulated device's plant, and
:func:`station.plant.simulate.simulate`'s loop for a Python controller), so every path
does the same float operations.

Effects of a :class:`station.plant.model.Model` (DESIGN.md "Model diagnosis contract"):
the command goes through the device's quantization, the amplifier's offset, saturation,
dead-zone and extra delay (before the first sample the device outputs 0, so the amplifier
outputs its offset); dry friction (Karnopp stick-slip: Coulomb, with a breakaway level
and the Stribeck curve when static_friction is above it) and backlash act inside the
plant on a sub-step grid dt/M of the same exact ZOH (friction through the command's
channel, backlash as a torque pair on motor and base); viscous friction, beam damping and
param:NAME are in the linear part. motor_polarity multiplies the amplifier's output (after
the delay: the whole torque turns around, dry friction still opposes the motion). The
sensors' faults act on the noise-free outputs before their quantization: θ·encoder_scale,
and accel_gain·a + accel_offset + accel_drift·k·dt at sample k of the run (k = 0 the run's
first sample; :class:`Stepper` counts its samples since ``reset``).

Imports the modal form, the rounding rule, the vocabulary's friction levels and
:func:`station.signals.shielded` (a stop is held while compiled code runs) only; a
Model is used through its methods (``linear_form``, ``linear_params``, ``effect_dict``),
so :mod:`station.plant.model` can build a `ModelPlant` without a circle.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from station.rig import DT
from station.plant.effects import friction_levels
from station.plant.modal import LinearForm
from station.rounding import half_away, sensor_count
from station.signals import shielded


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


def _outputs(z, cm, encoder_scale, accel_gain, accel_bias):  # pragma: no cover - compiled by numba
    """Noise-free (theta, a) at modal state z: Re(cm @ z), theta times encoder_scale, a
    times accel_gain plus accel_bias (the accelerometer's offset and drift at this sample)."""
    y0 = 0.0
    y1 = 0.0
    for i in range(z.shape[0]):
        y0 += (cm[0, i] * z[i]).real
        y1 += (cm[1, i] * z[i]).real
    return y0 * encoder_scale, y1 * accel_gain + accel_bias


def _amplifier(vk, offset, saturation, deadzone):  # pragma: no cover - compiled by numba
    """The amplifier's offset, saturation then dead-zone (DESIGN.md order), DAC counts
    (motor_polarity acts after the delay, at the amplifier's output)."""
    vk = vk + offset
    if vk > saturation:
        vk = saturation
    elif vk < -saturation:
        vk = -saturation
    if deadzone > 0.0:
        if vk > deadzone:
            vk = vk - deadzone
        elif vk < -deadzone:
            vk = vk + deadzone
        else:
            vk = 0.0
    return vk


def _advance(z, vk, lam, bm, bp, co, gw_v, gw_p, substeps, v_c, v_s, w_s, half_gap, k_d,
             c_d):  # pragma: no cover - compiled by numba
    """One sample with the torque command vk (DAC counts) held: z in place.

    substeps == 0: the linear ZOH step z <- lam z + bm vk. Else ``substeps`` steps of the
    sub-step grid, each with the backlash torque pair T and the dry friction f (counts,
    through the command's channel) held over the step: T = k_d·(δ − dz(δ)) +
    c_d·δ'·[|δ| <= half_gap] cancels what the drive spring/damper would transmit inside
    the gap. Friction (Karnopp): a moving motor slides against F(ω_m) = v_c + (v_s −
    v_c)·exp(−(ω_m/w_s)²) (ω_m at the step's start; v_c when v_s == v_c) while ω_m keeps
    its sign over the step; else f takes the value that stops the motor at the step's end
    when that is within ±v_s (stick), else ±v_s against the net torque (break-away).
    """
    n = z.shape[0]
    # complex x real as two real products: the same floats as complex(x) * complex(u, 0)
    # up to the sign of a zero, without the two products by zero (and no bp term without
    # backlash: adding t·bp = 0 changes no value either)
    if substeps == 0:
        for i in range(n):
            w = lam[i] * z[i]
            z[i] = complex(w.real + bm[i].real * vk, w.imag + bm[i].imag * vk)
        return
    stribeck = v_s > v_c
    for _ in range(substeps):
        dl = 0.0
        ddl = 0.0
        wm = 0.0
        wf = 0.0
        if half_gap > 0.0:
            for i in range(n):
                dl += co[0, i].real * z[i].real - co[0, i].imag * z[i].imag  # Re(co z)
                ddl += co[1, i].real * z[i].real - co[1, i].imag * z[i].imag
        if v_s > 0.0:
            for i in range(n):
                wm += co[2, i].real * z[i].real - co[2, i].imag * z[i].imag
                wf += co[3, i].real * z[i].real - co[3, i].imag * z[i].imag
        t = 0.0
        if half_gap > 0.0:
            if dl > half_gap:
                t = k_d * half_gap
            elif dl < -half_gap:
                t = -k_d * half_gap
            else:
                t = k_d * dl + c_d * ddl
        f = 0.0
        if v_s > 0.0:
            w_free = wf + gw_v * vk + gw_p * t  # ω_m at the step's end without friction
            sliding = False
            if wm != 0.0:
                sg = 1.0 if wm > 0.0 else -1.0
                level = v_c
                if stribeck:
                    r = wm / w_s
                    if r * r < 40.0:  # beyond, exp(-40) of the excess: below a float's resolution
                        level = v_c + (v_s - v_c) * math.exp(-r * r)
                if (w_free - gw_v * level * sg) * sg > 0.0:
                    f = level * sg
                    sliding = True
            if not sliding:
                f = w_free / gw_v
                if f > v_s:
                    f = v_s
                elif f < -v_s:
                    f = -v_s
        ue = vk - f
        if half_gap > 0.0:
            for i in range(n):
                w = lam[i] * z[i]
                z[i] = complex(w.real + bm[i].real * ue + bp[i].real * t, w.imag + bm[i].imag * ue + bp[i].imag * t)
        else:
            for i in range(n):
                w = lam[i] * z[i]
                z[i] = complex(w.real + bm[i].real * ue, w.imag + bm[i].imag * ue)


def _loop(lam, bm, bp, cm, co, gw_v, gw_p, substeps, z0, u, v_open, use_v_open, closed, gnum, gden, anum, aden,
          use_ga, limit, d, quantize, cmd_mode, store_mode, offset, saturation, deadzone, delay, accel_gain, v_c, v_s, w_s,
          half_gap, k_d, c_d, encoder_scale, accel_offset, accel_drift, polarity):  # pragma: no cover - compiled by numba
    n = u.shape[0]
    theta = np.zeros(n)
    acc = np.zeros(n)
    v = np.zeros(n)
    thd = np.zeros(n)
    z = z0.copy()
    gx = np.zeros(gnum.shape[0] - 1)  # Gth input history (newest first)
    gy = np.zeros(gden.shape[0] - 1)  # Gth output history: the saturated v
    ax = np.zeros(anum.shape[0] - 1)  # Ga input history
    ay = np.zeros(aden.shape[0] - 1)  # Ga output history
    # the amplifier's extra delay, samples; before the run the device output 0
    fifo = np.full(max(delay, 1), _amplifier(0.0, offset, saturation, deadzone))
    head = 0
    g_acc = 0.0
    a_acc = 0.0
    for k in range(n):
        y0, y1 = _outputs(z, cm, encoder_scale, accel_gain, accel_offset + accel_drift * k)
        if quantize:  # the sensors' reading (station.rounding.sensor_count)
            y0 = _sensor_count(y0)
            y1 = _sensor_count(y1)
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
                # the integer a lab's software stored (Compensator recursion), then its clamp
                if store_mode == 1:
                    vk = _half_away(vk)
                elif store_mode == 2:
                    vk = float(math.trunc(vk))
            else:
                vk = uk
            if vk > limit:
                vk = limit
            elif vk < -limit:
                vk = -limit
            if closed:
                g_acc = _commit(gnum, gden, gx, gy, e, vk)
                # the float remembered, its whole count sent (Compensator's SENT recursions)
                if store_mode == 3:
                    vk = _half_away(vk)
                elif store_mode == 4:
                    vk = float(math.trunc(vk))
        v[k] = vk
        thd[k] = td
        # what the device applies: whole DAC counts (the controller keeps the unrounded v)
        if cmd_mode == 1:
            vk = _half_away(vk)
        elif cmd_mode == 2:
            vk = float(math.trunc(vk))
        vk = _amplifier(vk, offset, saturation, deadzone)
        if delay > 0:
            out = fifo[head]
            fifo[head] = vk
            head = (head + 1) % delay
            vk = out
        _advance(z, vk * polarity, lam, bm, bp, co, gw_v, gw_p, substeps, v_c, v_s, w_s, half_gap, k_d, c_d)
    return theta, acc, v, thd


_half_away = half_away  # the device's command rounding (station.rounding), compiled by _compile
_sensor_count = sensor_count  # the sensors' quantization (station.rounding), compiled by _compile
_PLAIN = (_outputs, _amplifier, _advance)  # the per-sample functions as plain Python (same float operations)
_compiled_loop = None


def _compile() -> None:
    """Compile the kernel's functions with numba (or load them from numba's cache), once.

    Numba is imported here, on first use, not with the module: importing it and loading
    its cache costs most of a second of start-up, which a small linear plant stepped
    sample by sample does not need (:class:`Stepper`). Without numba everything stays
    plain Python (same results, about 1000x slower).
    """
    global _half_away, _sensor_count, _commit, _outputs, _amplifier, _advance, _compiled_loop
    if _compiled_loop is not None:
        return
    try:
        import numba  # lazy: start-up time (numba)
    except ImportError:  # pragma: no cover - exercised only without numba
        _compiled_loop = _loop
        return
    # lazy: start-up time (numba compiles these on first use)
    from station.rounding import half_away_compiled, sensor_count_compiled

    jit = numba.njit(cache=True, nogil=True)
    _half_away, _sensor_count = half_away_compiled, sensor_count_compiled
    _commit, _outputs, _amplifier, _advance = jit(_commit), jit(_outputs), jit(_amplifier), jit(_advance)
    _compiled_loop = jit(_loop)


def run_kernel(*args):
    """The whole run's sample loop, compiled on first use.

    Parameters
    ----------
    *args
        :func:`_loop`'s arguments in its order (:func:`station.plant.simulate.simulate`
        gives them).

    Returns
    -------
    theta, a, v, theta_d_hat : numpy.ndarray, shape (N,)

    Raises
    ------
    station.signals.StopSignal
        SIGINT or SIGTERM arrived during the call: held until the compiled code returned
        (:func:`station.signals.shielded`), raised then.
    """
    with shielded():  # a stop raised inside numba's dispatcher would come out as a SystemError
        _compile()
        return _compiled_loop(*args)


def coefficients(tf) -> tuple[np.ndarray, np.ndarray]:
    """A filter's (num, den) as the kernel takes them: contiguous floats, den[0] = 1.

    Parameters
    ----------
    tf : station.control.DiscreteTF or None
        Coefficients in z⁻¹; None gives (num [0], den [1]), a filter that is never used.
    """
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


class KernelEffects(NamedTuple):
    """A model's amplifier, output and in-plant effects as the kernel takes them.

    The defaults are no effects (a `DiscretePlant`); the fields are :func:`run_kernel`'s
    last arguments, in its order.

    Attributes
    ----------
    amp_offset : float
        Added to the command before the saturation, DAC counts.
    saturation : float
        The amplifier's clamp, DAC counts (inf: none).
    deadzone : float
        DAC counts.
    delay : int
        Extra samples between the command and the torque.
    accel_gain : float
        Scale of a before its quantization (negative: a reversed accelerometer).
    v_c : float
        Sliding (Coulomb) friction, DAC counts.
    v_s : float
        Breakaway friction, DAC counts (>= v_c; 0: no dry friction).
    w_s : float
        Stribeck speed, rad/s of the motor (used when v_s > v_c).
    half_gap : float
        Backlash / 2, rad.
    k_d, c_d : float
        Drive spring N·m/rad and damper N·m·s/rad of the linear part (backlash).
    encoder_scale : float
        Scale of θ before its quantization (measured / modelled counts).
    accel_offset : float
        Added to a before its quantization, accelerometer counts.
    accel_drift : float
        Added to a times the sample index k of the run, accelerometer counts per sample
        (the model's counts per s times dt).
    motor_polarity : float
        ±1: the amplifier's output (after its delay) times this is the torque command.
    """

    amp_offset: float = 0.0
    saturation: float = math.inf
    deadzone: float = 0.0
    delay: int = 0
    accel_gain: float = 1.0
    v_c: float = 0.0
    v_s: float = 0.0
    w_s: float = 1.0
    half_gap: float = 0.0
    k_d: float = 0.0
    c_d: float = 0.0
    encoder_scale: float = 1.0
    accel_offset: float = 0.0
    accel_drift: float = 0.0
    motor_polarity: float = 1.0


def effects_of(model, dt: float = DT) -> KernelEffects:
    """A Model's effects as the kernel takes them.

    Parameters
    ----------
    model : station.plant.model.Model
        Read through ``effect_dict()`` and ``linear_params()`` (drive spring, damper, H).
    dt : float, default 0.002
        Sample time, s (the accelerometer's drift per sample).
    """
    fx = model.effect_dict()
    p = model.linear_params()
    fr = friction_levels(fx)
    return KernelEffects(amp_offset=float(fx.get("amp_offset", 0.0)), saturation=float(fx.get("saturation", math.inf)),
                         deadzone=float(fx.get("deadzone", 0.0)), delay=int(fx.get("delay", 0)),
                         accel_gain=float(fx.get("accel_gain", 1.0)), v_c=fr.v_c, v_s=fr.v_s, w_s=fr.w_s,
                         half_gap=float(fx.get("backlash", 0.0)) / 2.0 / p.H, k_d=p.drive_k, c_d=p.drive_c,
                         encoder_scale=float(fx.get("encoder_scale", 1.0)),
                         accel_offset=float(fx.get("accel_offset", 0.0)),
                         accel_drift=float(fx.get("accel_drift", 0.0)) * float(dt),
                         motor_polarity=float(fx.get("motor_polarity", 1.0)))


def device_command(vk: float, cmd_mode: int) -> float:
    """The kernel's command quantization, for a Python loop (the same float operations).

    Parameters
    ----------
    vk : float
        The controller's command, DAC counts.
    cmd_mode : int
        A value of :data:`COMMAND_QUANTIZATION`: 0 none, 1 round (halves away from
        zero), 2 truncate toward zero.
    """
    if cmd_mode == 1:
        return half_away(vk)
    if cmd_mode == 2:
        return float(math.trunc(vk))
    return vk


PLAIN_MAX_STATES = 32
"""A linear form without sub-steps and with at most this many states (up to 6 beam elements)
is stepped in plain Python by default (:class:`ModelPlant`): tens of µs per sample, and no
compiler at start-up."""


class Stepper:
    """A linear form plus effects, stepped one sample at a time with the kernel's own functions.

    Parameters
    ----------
    form : LinearForm
        The linear part.
    fx : KernelEffects
        The amplifier, output and in-plant effects.
    z0 : array_like of complex, shape (n,), optional
        Initial modal state (default: at rest).
    compiled : bool, default True
        Step with the numba-compiled functions (compiled or loaded now, not on a real-time
        device's first tick); False: the same functions as plain Python (the same float
        operations, the same bits).

    Attributes
    ----------
    z : ndarray of complex, shape (n,)
        The current modal state.
    """

    def __init__(self, form: LinearForm, fx: KernelEffects, z0=None, compiled: bool = True) -> None:
        self._form = form
        self._fx = fx
        self._z0 = np.zeros(form.lam.size, complex) if z0 is None else np.asarray(z0, complex).copy()
        if compiled:
            _compile()
            self._fns = (_outputs, _amplifier, _advance)
        else:
            self._fns = _PLAIN
        self.reset()
        # compile (or load) the kernel's functions now, not on a real-time device's first tick
        self.outputs()
        self._fns[1](0.0, fx.amp_offset, fx.saturation, fx.deadzone)
        self._fns[2](self.z.copy(), 0.0, form.lam, form.bm, form.bp, form.co, form.gw_v, form.gw_p, form.substeps,
                     fx.v_c, fx.v_s, fx.w_s, fx.half_gap, fx.k_d, fx.c_d)

    def reset(self) -> None:
        """Back to the initial state (at rest for a model), the amplifier's delay line
        holding what it made of the device's 0 before the run, the sample count at 0 (the
        accelerometer's drift starts again)."""
        fx = self._fx
        self.z = self._z0.copy()
        self._fifo = [float(self._fns[1](0.0, fx.amp_offset, fx.saturation, fx.deadzone))] * fx.delay
        self._head = 0
        self._k = 0

    def outputs(self) -> tuple[float, float]:
        """Noise-free (theta, a) at the current sample: encoder counts, accelerometer counts
        (the sensors' faults applied: encoder_scale; accel_gain, offset and drift)."""
        fx = self._fx
        y0, y1 = self._fns[0](self.z, self._form.cm, fx.encoder_scale, fx.accel_gain,
                              fx.accel_offset + fx.accel_drift * self._k)
        return float(y0), float(y1)

    def advance(self, v: float) -> None:
        """One sample with the device's command v (DAC counts, already quantized by the
        device) through the amplifier's offset, saturation, dead-zone, delay and the motor's
        polarity into the plant.

        Parameters
        ----------
        v : float
            The command the device applies during the sample, DAC counts.
        """
        fx, f = self._fx, self._form
        _, amplifier, advance = self._fns
        vk = amplifier(float(v), fx.amp_offset, fx.saturation, fx.deadzone)
        if fx.delay > 0:
            vk, self._fifo[self._head] = self._fifo[self._head], vk
            self._head = (self._head + 1) % fx.delay
        advance(self.z, vk * fx.motor_polarity, f.lam, f.bm, f.bp, f.co, f.gw_v, f.gw_p, f.substeps, fx.v_c, fx.v_s,
                fx.w_s, fx.half_gap, fx.k_d, fx.c_d)
        self._k += 1


class ModelPlant(Stepper):
    """A :class:`station.plant.model.Model` stepped tick by tick, effects included.

    The interface of `DiscretePlant` that the simulated device uses (``reset``,
    ``outputs``, ``advance``); ``advance`` takes the command the device applies (after
    its own quantization and clamp) and passes it through the amplifier's offset,
    saturation, dead-zone, delay and the motor's polarity; friction and backlash act inside
    the plant on the sub-step grid; ``outputs`` applies the sensors' faults (encoder_scale,
    accel_gain, accel_offset, accel_drift from the last ``reset``: on the simulated device
    that is the run's start, v1 START or legacy 'q', so the station's zeroing before tick 0
    reads the offset and removes it, as it would on the rig). Sample for sample equal to
    :func:`station.plant.simulate.simulate` with the same model (the same compiled
    functions do the arithmetic).

    Parameters
    ----------
    model : Model
    dt : float, default 0.002
        Sample time, s.
    substeps : int, optional
        Sub-steps per sample with friction or backlash (default :data:`station.plant.model.SUBSTEPS`).
    compiled : bool, optional
        As :class:`Stepper`; default: plain Python for a linear form without sub-steps of at
        most :data:`PLAIN_MAX_STATES` states (the default model: the simulated rig starts
        without a compiler), compiled otherwise.

    Attributes
    ----------
    model, dt, n_elements
        As given.
    params : Params
        The model's nominal parameter set.
    """

    def __init__(self, model, dt: float = DT, substeps: int | None = None, compiled: bool | None = None) -> None:
        self.model = model
        self.dt = float(dt)
        self.n_elements = model.n_elements
        self.params = model.params
        form = model.linear_form(self.dt, substeps)
        if compiled is None:
            compiled = form.substeps > 0 or form.lam.size > PLAIN_MAX_STATES
        super().__init__(form, effects_of(model, self.dt), compiled=compiled)

