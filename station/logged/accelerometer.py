"""The accelerometer: whether a reads the tip at all, and whether its mass was on the beam.

**A silent channel.** :func:`station.logged.audit.accel_claims` finds an a column that creeps.
One that reads its noise at rest all through a run that moved the beam is no tip acceleration
either (:func:`silent_claims`): its 1-40 Hz band (:func:`station.logged.audit.accel_band`)
stays under :data:`station.logged.audit.ACCEL_SIGNAL_RATIO` times its noise at rest while the
nominal model, driven open loop by the command the run applied and scaled by how far the hub
moved against the model's, puts :data:`SILENT_MODEL_RATIO` (6.7) times that noise there: an accelerometer of the
fit's least gain, 0.3, would read at least the 2 times that makes a signal. (Scaled so,
the model's 11.7 counts on the blind 21 s sweep become 3.7 under a Coulomb friction of 28 DAC
counts, what an accelerometer there reads.) The rig's logs with the accelerometer read 4-58
times their noise.

**Its mass.** The model carries the accelerometer at the beam's tip: a point mass m_accel
(6.1 g) and a rotary inertia J_accel. A run whose a column reads the tip was run with it
there. A run whose a column is no tip acceleration leaves the question open: the
accelerometer may be unplugged on the tip, or taken off the beam, as on the rig's 28 Jan 2014
sweep ``without_accel_01_28_14_test_2``. Its mass moves the beam's first hub-held mode, which
θ/v shows as its first antiresonance: tmm-fit puts it at 2.55 Hz with the mass and 3.00 Hz
without. :func:`decide_mounting` finds the notch of the run's θ/v (the H1 estimate,
:func:`station.analysis.frequency.band_notch`) between :data:`BAND_BELOW` times the first and
:data:`BAND_ABOVE` times the second, and places it on the log scale between the two: within
:data:`DECIDED_SHARE` of the way from one, the run had that configuration; a notch too shallow
(:data:`NOTCH_DEPTH`), a band the command does not excite (:data:`NOTCH_COHERENCE`), a run
shorter than two Welch segments of 4 s (a step), or a notch between the two leaves it
unchecked, and the run keeps the model's accelerometer.

On the rig's sweeps with the accelerometer (2009's three, the 2013-14 swept sine, the 28 Jan
2014 sweep with it) the notch is at 2.55-2.61 Hz; on the 28 Jan sweep without it, 3.19 Hz
(``tests/test_accelerometer.py``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from station.logged.audit import ACCEL_CLAIM, ACCEL_SIGNAL_RATIO, AuditClaim, accel_band
from station.plant.effects import EFFECTS

ACCEL_GAIN_LEAST = EFFECTS["accel_gain"].lower
"""The least accelerometer gain a still channel is told from (accel_gain's magnitude where the fit
searches it, :data:`station.plant.effects.EFFECTS`): a quieter accelerometer reads under twice
its noise on the rig's runs and cannot be told from an unplugged one."""

SILENT_MODEL_RATIO = ACCEL_SIGNAL_RATIO / ACCEL_GAIN_LEAST
"""A still a column is no tip acceleration when the model puts this many times its noise at
rest in its band (module docstring): an accelerometer of the least gain would read
:data:`station.logged.audit.ACCEL_SIGNAL_RATIO` times its noise there."""

MOTION_HORIZON_S = 0.05
"""Horizon of the θ changes that compare how far the hub moved with the model's, s."""


def silent_claims(a, dt: float, rest_samples: int, expected) -> list[AuditClaim]:
    """The a column's claim to be a tip acceleration, checked by its silence (module docstring).

    Parameters
    ----------
    a : array_like, shape (N,)
        The logged a, counts.
    dt : float
        Sample time, s.
    rest_samples : int
        Samples at rest before the first command.
    expected : callable
        ``expected() -> (model_a, motion)`` or None: the nominal model's a for the run
        (counts, shape (N,)) and how far the hub moved against the model's (the ratio of θ's
        changes' RMS); called only when a is still; None when the run cannot be simulated.

    Returns
    -------
    list of AuditClaim
        Empty, or one contradicted "columns" claim with header
        :data:`station.logged.audit.ACCEL_CLAIM` (a unused).
    """
    band = accel_band(a, dt, rest_samples)
    if band is None or band[0] >= ACCEL_SIGNAL_RATIO * band[1]:
        return []
    reads, noise = band
    got = expected()
    if got is None:
        return []
    model_a, motion = got
    model_band = accel_band(model_a, dt, rest_samples)
    if model_band is None:
        return []
    would = model_band[0] * min(1.0, motion)
    if would < SILENT_MODEL_RATIO * noise:
        return []
    return [AuditClaim("columns", ACCEL_CLAIM, "a is no tip acceleration: it reads noise where the tip moved (its "
                       "accelerometer is not used)", "contradicted",
                       f"a's 1-40 Hz band after the rest is {reads:.2f} counts RMS, {reads / noise:.1f} times its noise "
                       f"at rest ({noise:.2f}); an accelerometer on the tip would read about {would:.1f} (the nominal "
                       f"model's {model_band[0]:.1f}, the hub moving {min(1.0, motion):.2f} of the model's): the "
                       f"accelerometer is unplugged or off the beam")]


def motion_ratio(theta, theta_model, dt: float) -> float:
    """How far the hub moved against the model's: the RMS of θ's changes over
    :data:`MOTION_HORIZON_S` over the model's (0 when the model's hub stands still).

    Parameters
    ----------
    theta, theta_model : array_like, shape (N,)
        Logged and modelled θ, encoder counts.
    dt : float
        Sample time, s.

    Returns
    -------
    float
    """
    h = max(1, int(round(MOTION_HORIZON_S / dt)))
    t, m = np.asarray(theta, float), np.asarray(theta_model, float)
    if t.size <= h:
        return 0.0
    dm = float(np.sqrt(np.mean((m[h:] - m[:-h]) ** 2)))
    return 0.0 if dm <= 0 else float(np.sqrt(np.mean((t[h:] - t[:-h]) ** 2))) / dm

MOUNTED_CLAIM = "a: an accelerometer on the beam's tip (its mass and rotary inertia in the model)"
"""What every log claims about the beam (the model's accelerometer at the tip)."""

BAND_BELOW, BAND_ABOVE = 0.8, 1.25
"""The notch is searched from BAND_BELOW times the model's first antiresonance with the
accelerometer's mass to BAND_ABOVE times the one without it."""

NOTCH_DEPTH = 0.5
"""Largest |θ/v| at the notch over that at the band's ends for a notch (the rig's sweeps:
0.09-0.33)."""

NOTCH_COHERENCE = 0.5
"""Least median coherence of θ/v over the band: the command excites it (the rig's sweeps:
0.87-0.96)."""

DECIDED_SHARE = 1.0 / 3.0
"""A notch within this share of the log distance between the two models' antiresonances
from one of them (or beyond it) decides that configuration."""


@dataclass(frozen=True)
class Mounting:
    """Whether the accelerometer's mass was on the beam in a run (:func:`decide_mounting`).

    Attributes
    ----------
    mounted : bool or None
        True: on the beam (the model as it is); False: off (the run is simulated with
        ``accel_mounted`` 0); None: the data cannot tell (the model as it is).
    claim : AuditClaim or None
        The "columns" claim :data:`MOUNTED_CLAIM`: confirmed, contradicted or unchecked; None
        when the question is not open (a reads the tip: its accelerometer is on the beam).
    measured_hz, with_hz, without_hz : float or None
        The run's θ/v notch and the nominal model's first antiresonance with and without the
        accelerometer's mass, Hz.
    """

    mounted: bool | None
    claim: AuditClaim | None = None
    measured_hz: float | None = None
    with_hz: float | None = None
    without_hz: float | None = None


ON_THE_TIP = Mounting(True)
"""An accelerometer that reads the tip is on the beam: no claim to check."""


@functools.lru_cache(maxsize=1)
def nominal_antiresonances() -> tuple[float, float]:
    """tmm-fit's first θ/v antiresonance with and without the accelerometer's mass, Hz
    (:func:`station.plant.modes.modal_summary`, 4 elements)."""
    # lazy: start-up time (the FEM and scipy.linalg, only for a log whose a reads no tip)
    from station.plant import load_params
    from station.plant.modes import modal_summary

    p = load_params("tmm-fit")
    off = dataclasses.replace(p, m_accel=0.0, J_accel=0.0)
    return (float(modal_summary(p, 4, 40.0).antiresonances_hz[0]),
            float(modal_summary(off, 4, 40.0).antiresonances_hz[0]))


def decide_mounting(v, theta, dt: float) -> Mounting:
    """Decide from θ/v whether the accelerometer's mass was on the beam (module docstring).

    Parameters
    ----------
    v : array_like, shape (N,)
        The command the plant received, DAC counts.
    theta : array_like, shape (N,)
        The hub angle, encoder counts.
    dt : float
        Sample time, s.

    Returns
    -------
    Mounting
        With its "columns" claim: contradicted (off the beam), confirmed (on it) or unchecked.
    """
    # lazy: start-up time (scipy.signal and python-control, only for a log whose a reads no tip)
    from station.analysis.frequency import band_notch

    f_on, f_off = nominal_antiresonances()
    band = (BAND_BELOW * f_on, BAND_ABOVE * f_off)
    models = f"the model's {f_on:.2f} Hz with its mass, {f_off:.2f} Hz without"
    notch = band_notch(v, theta, dt, band)
    where = f"{band[0]:.2f}-{band[1]:.2f} Hz"

    def unchecked(why: str) -> Mounting:
        return Mounting(None, AuditClaim("columns", MOUNTED_CLAIM, "undecided", "unchecked",
                                         f"a reads no tip acceleration, so its mass may be off the beam; {why}: the "
                                         f"model keeps the accelerometer ({models})"), None, f_on, f_off)

    if notch is None:
        return unchecked(f"the run ({np.asarray(theta).size * dt:.3g} s) is too short to estimate θ/v's "
                         f"first antiresonance in {where} (two Welch segments of 4 s)")
    seen = (f"H1 estimate of θ/v (Welch, {notch.nperseg} samples): notch at {notch.frequency_hz:.2f} Hz, "
            f"|θ/v| there {notch.depth:.2f} of the band's ends, median coherence {notch.coherence:.2f} in {where}")
    if not notch.inside or notch.depth > NOTCH_DEPTH or notch.coherence < NOTCH_COHERENCE:
        return unchecked(f"{seen}: no antiresonance there (a notch has |θ/v| under {NOTCH_DEPTH:g} of the band's "
                         f"ends, inside the band, coherence at least {NOTCH_COHERENCE:g})")
    x = math.log(notch.frequency_hz / f_on) / math.log(f_off / f_on)  # 0: with the mass, 1: without
    line = f"θ/v's first antiresonance {notch.frequency_hz:.2f} Hz, {models}"
    if x >= 1.0 - DECIDED_SHARE:
        return Mounting(False, AuditClaim("columns", MOUNTED_CLAIM, f"no accelerometer on the beam: {line}",
                                          "contradicted", f"{seen}: nearer the model without the accelerometer's "
                                          f"mass; the run is simulated without it (accel_mounted 0)"),
                        notch.frequency_hz, f_on, f_off)
    if x <= DECIDED_SHARE:
        return Mounting(True, AuditClaim("columns", MOUNTED_CLAIM, f"the accelerometer's mass on the beam: {line}",
                                         "confirmed", f"{seen}: nearer the model with the accelerometer's mass (its "
                                         f"a reads no tip acceleration: unplugged, or not read)"),
                        notch.frequency_hz, f_on, f_off)
    return unchecked(f"{seen}: between the two")
