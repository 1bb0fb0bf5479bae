"""One run's θ and a against the nominal model driven open loop by the command the run
applied: the evidence :func:`station.logged.sensors.decide_faults` decides the sensors' signs,
scales and bias from (DESIGN.md's sensor and wiring faults).

- θ: the cosine between the measured and the modelled θ's changes over
  :data:`THETA_HORIZON_S` where the measured hub moved (short, and moving, so the model's
  drift without friction does not count), and the least-squares ratio of the measured to
  the modelled changes;
- a: the cosine between the measured and the modelled a in each octave of
  :data:`ACCEL_OCTAVES_HZ` (1-40 Hz: the accelerometer's offset and drift, and the beam's
  rigid motion, removed) where the model's a has :data:`OCTAVE_SHARE` of its largest octave's
  RMS, the median over those octaves; a's least-squares ratios over the whole band and over
  the octaves whose cosine reaches :data:`station.logged.sensors.SIGN_COSINE`; and a's bias and
  drift, the least-squares fit of the measured a on [1, t, the model's a], with its rest before
  the first command and the drift its integral gives where the run ends at rest (no model in
  either).
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass

import numpy as np

from station.control.rerun import OpenLoop
from station.logged.audit import ACCEL_BAND_HZ
from station.logged.device import command_quantization

REST_MIN_SAMPLES = 5
"""Fewest samples before the first command that give the accelerometer's rest offset."""

SIGN_COSINE = 0.5
"""|cosine| at or above which a sign is decided (:mod:`station.logged.sensors`); the ratio of a
is taken over the octaves whose cosine reaches it."""

THETA_HORIZON_S = 0.05
"""Horizon of the θ changes compared, s."""

ACCEL_OCTAVES_HZ = (1.0, 2.0, 4.0, 8.0, 16.0, 40.0)
"""Edges of the bands a's cosines are taken in, Hz (second-order Butterworth, forward and
backward): octaves across :data:`station.logged.audit.ACCEL_BAND_HZ`, the last one wider."""

OCTAVE_SHARE = 0.1
"""An octave's cosine counts where the model's a there has at least this share of its largest
octave's RMS (and at least :data:`OCTAVE_FLOOR_COUNTS`): an octave the run hardly moves is the
noise's."""

OCTAVE_FLOOR_COUNTS = 0.6
"""Least RMS of the model's a in an octave whose cosine counts, counts (twice the
accelerometer's noise)."""

MOVING_COUNTS = 2.0
"""θ changes are compared where the measured hub moved at least this many counts over
:data:`THETA_HORIZON_S` (a sticking hub while the frictionless model drifts says nothing about
the encoder)."""

MIN_WINDOWS = 20
"""Fewest moving windows a run's θ comparison needs."""

END_REST_S = 0.25
"""The run's last stretch, s, whose motion bounds the tip's speed at the end
(:func:`integral_drift`): half a period of the beam's slowest ringing (2 Hz; its first mode is
2.5 Hz with the accelerometer on the tip), so that a's integral over it ranges over at least the
ringing speed's amplitude."""

TIP_PER_HUB = 0.41 * 1.145 / (1024 / (2 * math.pi))
"""The tip's speed, accelerometer counts·s, per hub speed of one encoder count per s: the beam's
0.41 m times the accelerometer's 1.145 counts per m/s² (tmm-fit) over 1024/2π counts per rad."""

END_DRIFT_ERROR = 0.5
"""Most the tip's speed at the run's end may move a drift read from a's integral, counts per s:
the bound on that speed (a's ringing, the hub's motion: :func:`integral_drift`) over the integral of
the time since the rest (a 2 s run: 1.9 s², a 1 s run 0.5 s²)."""

@dataclass(frozen=True)
class SensorEvidence:
    """One run's θ and a against the nominal model driven by the run's applied command.

    Attributes
    ----------
    name : str
        The run's file name.
    theta_cosine, theta_ratio : float or None
        Cosine and least-squares ratio (measured / model) of θ's changes over
        :data:`THETA_HORIZON_S`; None when either did not move.
    accel_cosine : float or None
        The same for a, the median over the octaves that count (:func:`octave_compare`);
        None when either is flat, the band reaches the Nyquist frequency or the log's a is
        no tip acceleration (its audit).
    accel_ratio : float or None
        a's least-squares ratio over all of :data:`ACCEL_BAND_HZ` at once; None as
        ``accel_cosine``.
    accel_bias, accel_slope : float or None
        a's bias (counts: its rest value before the first command plus what remains) and its
        drift (counts per s) beside the model's a: the least-squares fit of the measured a on
        [1, t, the model's a] over the whole run; None as ``accel_cosine``.
    accel_band_cosine : float or None
        a's cosine over all of :data:`ACCEL_BAND_HZ` at once, where its ratio measures a gain
        (:func:`decide_faults`); None as ``accel_cosine``.
    accel_shaped_ratio : float or None
        a's ratio over the octaves whose shape the model has (:func:`octave_compare`); None as
        ``accel_cosine``.
    accel_rest : float or None
        a's mean before the first command, counts (:attr:`station.logged.LoggedRun.accel_rest_offset`:
        nothing of the model in it); None as ``accel_cosine`` or with too few samples at rest.
    accel_integral_drift : float or None
        a's drift from its integral, counts per s (:func:`integral_drift`: no model in it); None
        as ``accel_rest`` or where the run does not end at rest.
    """

    name: str
    theta_cosine: float | None
    theta_ratio: float | None
    accel_cosine: float | None
    accel_ratio: float | None
    accel_bias: float | None = None
    accel_slope: float | None = None
    accel_band_cosine: float | None = None
    accel_shaped_ratio: float | None = None
    accel_rest: float | None = None
    accel_integral_drift: float | None = None


def integral_drift(a, theta, rest: int, dt: float) -> float | None:
    """An accelerometer's drift from its integral: where the tip is at rest before the first
    command and at the end, its acceleration integrates to nothing over the run, and a's
    integral less its rest value from the first command on is the drift's alone: d times the
    integral of the time from the rest's middle.

    Parameters
    ----------
    a, theta : array_like, shape (N,)
        The logged a (accelerometer counts) and θ (encoder counts).
    rest : int
        Samples at rest before the first command (:attr:`station.logged.LoggedRun.accel_rest_samples`).
    dt : float
        Sample time, s.

    Returns
    -------
    float or None
        d, counts per s; None with fewer than :data:`REST_MIN_SAMPLES` samples at rest, a run
        of under 0.5 s after them, or where the tip's speed at the end could move d by more than
        :data:`END_DRIFT_ERROR`: its ringing, bounded by the range of a's integral over the last
        :data:`END_REST_S` (a less its mean there), and the hub's motion there times
        :data:`TIP_PER_HUB`.
    """
    a, theta = np.asarray(a, float), np.asarray(theta, float)
    w = max(2, int(round(END_REST_S / dt)))
    if rest < REST_MIN_SAMPLES or (a.size - rest) * dt < 0.5 or a.size - rest < w or not np.all(np.isfinite(a)):
        return None
    # a less its rest mean integrates d·(t - the rest's middle) from the first command on, plus
    # the tip's speed at the end
    k = np.arange(rest, a.size) - 0.5 * (rest - 1)
    g = float(np.sum(k)) * dt * dt
    ringing = float(np.ptp(np.cumsum(a[-w:] - np.mean(a[-w:])))) * dt
    speed = ringing + abs(float(theta[-1] - theta[-w])) / (w * dt) * TIP_PER_HUB
    if not math.isfinite(speed) or speed / g > END_DRIFT_ERROR:
        return None
    return float(np.sum(a[rest:] - np.mean(a[:rest])) * dt / g)


def cosine_ratio(measured: np.ndarray, model: np.ndarray) -> tuple[float | None, float | None]:
    """The cosine of two signals and the least-squares ratio of the first over the second.

    Parameters
    ----------
    measured, model : ndarray, shape (N,)

    Returns
    -------
    (float, float) or (None, None)
        (None, None) when either is all zero or not finite.
    """
    nm, ns = float(np.linalg.norm(measured)), float(np.linalg.norm(model))
    if not (nm > 0 and ns > 0 and math.isfinite(nm) and math.isfinite(ns)):
        return None, None
    dot = float(measured @ model)
    return dot / (nm * ns), dot / (ns * ns)


def sensor_evidence(run, model) -> SensorEvidence:
    """Compare a run's θ and a with the model driven open loop by the run's applied command.

    Parameters
    ----------
    run : station.logged.LoggedRun
        With t, u, v, θ and a.
    model : station.plant.model.Model
        The nominal model (its effects apply).

    Returns
    -------
    SensorEvidence
    """
    # lazy: start-up time (scipy's filters)
    from scipy.signal import butter, sosfiltfilt

    # lazy: start-up time (the FEM and its compiled kernels, loaded when used)
    from station.plant import simulate

    log, dt = run.log, run.log.dt
    d = log.data
    name = log.path.name if log.path is not None else "log"
    if len(run) < 50:
        return SensorEvidence(name, None, None, None, None)
    model = run.model_for(model)  # the accelerometer's mass off the beam when the audit says so
    applied = d["v_applied"]
    if applied.size and np.all(np.isfinite(applied)):
        pred = simulate(model, OpenLoop(), d["u"], alignment=0, v_open=applied, dt=dt)
    else:
        pred = simulate(model, OpenLoop(), d["u"], alignment=0, v_open=d["v"], command=command_quantization(log),
                        dt=dt)
    h = max(1, int(round(THETA_HORIZON_S / dt)))
    theta, theta_m = np.asarray(d["theta"], float), np.asarray(pred["theta"], float)
    dm, ds = theta[h:] - theta[:-h], theta_m[h:] - theta_m[:-h]
    moving = np.abs(dm) >= MOVING_COUNTS  # a stuck hub is friction's, not the sensor's: not compared
    th = cosine_ratio(dm[moving], ds[moving]) if np.count_nonzero(moving) >= MIN_WINDOWS else (None, None)
    nyquist = 0.5 / dt
    a_raw = np.asarray(d["a"], float)
    if run.accel_is_tip and len(run) > 30 and ACCEL_BAND_HZ[1] < nyquist and np.all(np.isfinite(a_raw)):
        sos = butter(2, ACCEL_BAND_HZ, "bandpass", fs=1.0 / dt, output="sos")
        rest = run.accel_rest_offset
        a, a_m = a_raw - rest, np.asarray(pred["a"], float)
        band = cosine_ratio(sosfiltfilt(sos, a), sosfiltfilt(sos, a_m))
        octaves = octave_compare(a, a_m, dt)
        if band[0] is not None and octaves[0] is not None:
            t = np.arange(a.size) * dt  # the plant's drift runs from the run's first sample
            (bias, slope, _), *_ = np.linalg.lstsq(np.column_stack([np.ones_like(t), t, a_m]), a, rcond=None)
            at_rest = run.accel_rest_samples >= REST_MIN_SAMPLES
            return SensorEvidence(name, *th, octaves[0], band[1], float(rest + bias), float(slope), band[0],
                                  octaves[1], rest if at_rest else None,
                                  integral_drift(a_raw, theta, run.accel_rest_samples, dt))
    return SensorEvidence(name, *th, None, None)


def octave_compare(measured, model, dt: float) -> tuple[float | None, float | None]:
    """The cosine and the least-squares ratio (measured / model) of a, from the octaves of
    :data:`ACCEL_OCTAVES_HZ` where the model's a has :data:`OCTAVE_SHARE` of its largest
    octave's RMS and at least :data:`OCTAVE_FLOOR_COUNTS` (the largest always counts): the
    median of their cosines, and the ratio over those whose cosine reaches
    :data:`SIGN_COSINE` either way (all of them when none does), each weighted by its energy
    as one least-squares fit.

    Parameters
    ----------
    measured, model : array_like, shape (N,)
        a, counts, the measured one less its rest offset.
    dt : float
        Sample time, s (octaves at or past the Nyquist frequency are left out).

    Returns
    -------
    (float, float) or (None, None)
        The cosine in [-1, 1] and the ratio; None when no octave has both signals.
    """
    # lazy: start-up time (scipy's filters)
    from scipy.signal import butter, sosfiltfilt

    x, y = np.asarray(measured, float), np.asarray(model, float)
    nyquist = 0.5 / dt
    octaves = []  # (cosine, ratio, the model's RMS)
    for lo, hi in zip(ACCEL_OCTAVES_HZ[:-1], ACCEL_OCTAVES_HZ[1:]):
        if hi >= nyquist:
            break
        sos = butter(2, (lo, hi), "bandpass", fs=1.0 / dt, output="sos")
        xb, yb = sosfiltfilt(sos, x), sosfiltfilt(sos, y)
        c = cosine_ratio(xb, yb)[0]
        if c is not None:
            octaves.append((c, float(xb @ yb), float(yb @ yb)))
    if not octaves:
        return None, None
    least = max(OCTAVE_SHARE ** 2 * max(o[2] for o in octaves), OCTAVE_FLOOR_COUNTS ** 2 * x.size)
    counted = [o for o in octaves if o[2] >= least] or [max(octaves, key=lambda o: o[2])]
    cosine = float(statistics.median(o[0] for o in counted))
    # the ratio over the octaves whose shape the model has (least squares across them): an
    # octave the model's mode misses would pull it toward 0
    shaped = [o for o in counted if abs(o[0]) >= SIGN_COSINE] or counted
    return cosine, sum(o[1] for o in shaped) / sum(o[2] for o in shaped)
