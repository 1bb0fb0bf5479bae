"""Frequency responses: the H1 estimate from a measured run and the FEM model's response.

The H1 estimator of the transfer function from x to y is Ĥ1(f) = P_xy(f)/P_xx(f), the
Welch-averaged cross spectrum over the input's auto spectrum (Bendat & Piersol), with
the magnitude-squared coherence γ²(f) = |P_xy|²/(P_xx P_yy) telling where it can be
trusted. For the rig, x = v (DAC counts) and y = θ or a (counts), sampled at 500 Hz.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
import scipy.signal

from station.plant.discrete import DiscretePlant
from station.plant.modes import modal_summary


@dataclass(frozen=True)
class FrequencyEstimate:
    """An estimated frequency response.

    Attributes
    ----------
    f : ndarray, shape (F,)
        Frequencies, Hz.
    H : ndarray of complex, shape (F,)
        Ĥ1 = P_xy / P_xx (output units per input unit, e.g. counts per DAC count).
    coherence : ndarray, shape (F,)
        Magnitude-squared coherence γ², 0..1.
    """

    f: np.ndarray
    H: np.ndarray
    coherence: np.ndarray


def h1_estimate(x, y, fs: float, nperseg: int = 4096) -> FrequencyEstimate:
    """H1 frequency-response estimate from input x to output y, with coherence.

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Input and output samples (e.g. v in DAC counts and θ in encoder counts).
    fs : float
        Sample rate, Hz.
    nperseg : int, default 4096
        Welch segment length (Hann window, 50 % overlap); resolution fs/nperseg Hz.

    Returns
    -------
    FrequencyEstimate
        From scipy.signal.csd, scipy.signal.welch and scipy.signal.coherence.

    Raises
    ------
    ValueError
        x and y differ in shape or are shorter than one segment.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape != y.shape or x.ndim != 1:
        raise ValueError(f"x and y must be 1-D arrays of the same length, got {x.shape} and {y.shape}")
    if x.size < nperseg:
        raise ValueError(f"{x.size} samples are fewer than one Welch segment ({nperseg})")
    f, pxx = scipy.signal.welch(x, fs=fs, nperseg=nperseg)
    _, pxy = scipy.signal.csd(x, y, fs=fs, nperseg=nperseg)
    _, coh = scipy.signal.coherence(x, y, fs=fs, nperseg=nperseg)
    with np.errstate(divide="ignore", invalid="ignore"):
        H = pxy / pxx
    return FrequencyEstimate(f, H, coh)


def model_response(plant, f) -> np.ndarray:
    """Frequency response of the sampled FEM plant from v to [θ, a].

    Parameters
    ----------
    plant : station.plant.DiscretePlant
        The exact-ZOH model; its response is what a log's v → θ, a relation shows
        (θ[k] sees x_k, so the one-sample hold and delay are included).
    f : array_like, shape (F,)
        Frequencies, Hz, 0 < f <= Nyquist (f = 0 is the rigid-body integrator's pole).

    Returns
    -------
    ndarray of complex, shape (2, F)
        θ/v (encoder counts per DAC count) and a/v (accelerometer counts per DAC count)
        at z = exp(j 2π f dt) (python-control's frequency_response).

    Raises
    ------
    ValueError
        A frequency is not in (0, Nyquist].
    """
    f = np.asarray(f, dtype=float)
    if np.any(f <= 0) or np.any(f > 0.5 / plant.dt):
        raise ValueError(f"frequencies must lie in (0, {0.5 / plant.dt:g}] Hz")
    sys = control.ss(plant.Ad, plant.Bd[:, None], plant.Cd, np.zeros((2, 1)), plant.dt)
    resp = sys.frequency_response(2 * np.pi * f)
    return np.asarray(resp.complex)[:, 0, :]


def notch_frequencies(f, H, near, rel_window: float = 0.25) -> np.ndarray:
    """Frequencies of the deepest notch of |H| near given frequencies (antiresonances).

    Parameters
    ----------
    f : array_like, shape (F,)
        Frequencies, Hz, ascending and evenly spaced.
    H : array_like of complex, shape (F,)
        Frequency response.
    near : array_like, shape (R,)
        Expected antiresonance frequencies, Hz (e.g. the model's).
    rel_window : float, default 0.25
        Search window ±rel_window·near.

    Returns
    -------
    ndarray, shape (R,)
        For each expected frequency, the minimum of |H| in its window refined by
        parabolic interpolation of log|H| over the neighbouring bins, Hz; NaN when
        the window holds fewer than three bins.
    """
    f = np.asarray(f, dtype=float)
    mag = np.log(np.abs(np.asarray(H)) + 1e-300)
    out = []
    for fc in np.atleast_1d(near):
        idx = np.flatnonzero((f >= fc * (1 - rel_window)) & (f <= fc * (1 + rel_window)))
        if idx.size < 3:
            out.append(np.nan)
            continue
        i = idx[np.argmin(mag[idx])]
        if 0 < i < f.size - 1:
            a, b, c = mag[i - 1], mag[i], mag[i + 1]
            den = a - 2 * b + c
            shift = min(max(0.5 * (a - c) / den, -0.5), 0.5) if den > 0 else 0.0
            out.append(f[i] + shift * (f[1] - f[0]))
        else:
            out.append(f[i])
    return np.array(out)


NOTCH_MIN_SEGMENT = 2048
"""Shortest Welch segment :func:`band_notch` estimates with, samples (0.24 Hz at the rig's rate)."""


@dataclass(frozen=True)
class BandNotch:
    """The deepest notch of a measured response in a band (:func:`band_notch`).

    Attributes
    ----------
    frequency_hz : float
        Where |Ĥ1| is smallest in the band, refined by :func:`notch_frequencies`, Hz.
    depth : float
        |Ĥ1| at that bin over the geometric mean of |Ĥ1| at the band's first and last bins
        (a notch: well under 1).
    coherence : float
        Median magnitude-squared coherence γ² over the band's bins (how well the input
        excites the band; the notch's own bins dip).
    inside : bool
        The smallest |Ĥ1| is not at the band's first or last bin (a notch, not a slope).
    nperseg : int
        Welch segment length used, samples.
    """

    frequency_hz: float
    depth: float
    coherence: float
    inside: bool
    nperseg: int


def band_notch(x, y, dt: float, band: tuple[float, float], max_nperseg: int = 4096) -> BandNotch | None:
    """The deepest notch of the H1 estimate of y/x in a frequency band (e.g. θ/v's first
    antiresonance, between where two models put it).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Input and output samples (e.g. the applied command v and θ).
    dt : float
        Sample time, s.
    band : (float, float)
        Lowest and highest frequency searched, Hz.
    max_nperseg : int, default 4096
        Longest Welch segment; the segment is the longest power of two up to it that fits
        twice in the run.

    Returns
    -------
    BandNotch or None
        None when the run is shorter than two segments of :data:`NOTCH_MIN_SEGMENT` samples,
        x is constant, or the band holds fewer than three bins or lies past the Nyquist
        frequency.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    lo, hi = band
    nperseg = max_nperseg
    while nperseg > NOTCH_MIN_SEGMENT and 2 * nperseg > x.size:
        nperseg //= 2
    if 2 * nperseg > x.size or hi >= 0.5 / dt or not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))) \
            or np.ptp(x) == 0:  # no command: nothing to estimate from
        return None
    est = h1_estimate(x, y, 1.0 / dt, nperseg)
    idx = np.flatnonzero((est.f >= lo) & (est.f <= hi))
    mag = np.abs(est.H)
    if idx.size < 3 or not np.all(np.isfinite(mag[idx])) or mag[idx[0]] <= 0 or mag[idx[-1]] <= 0:
        return None
    i = int(idx[np.argmin(mag[idx])])
    f = float(notch_frequencies(est.f, est.H, [0.5 * (lo + hi)], (hi - lo) / (hi + lo))[0])
    return BandNotch(f, float(mag[i] / np.sqrt(mag[idx[0]] * mag[idx[-1]])), float(np.median(est.coherence[idx])),
                     bool(idx[0] < i < idx[-1]), nperseg)


def phase_beside(H, reference) -> np.ndarray:
    """The phase of ``H`` in degrees, unwrapped onto the branch of ``reference``'s.

    Unwrapping a measured and a model response each on its own can leave them a whole turn
    (360°) apart where noise or a notch makes one jump: the plot then shows a gap that is no
    error. Here the measured phase is the reference's unwrapped phase plus the wrapped
    difference, so the two are never more than 180° apart and a real phase error shows as it is.

    Parameters
    ----------
    H, reference : array_like of complex, shape (n,)
        Responses at the same frequencies (e.g. the H1 estimate and the model's θ/v).

    Returns
    -------
    numpy.ndarray, shape (n,)
        ∠H in degrees, with ``|result - unwrap(∠reference)| <= 180``.
    """
    H = np.asarray(H, dtype=complex)
    reference = np.asarray(reference, dtype=complex)
    return np.degrees(np.unwrap(np.angle(reference)) + np.angle(H / reference))


@dataclass(frozen=True)
class BodeComparison:
    """Measured (H1) and modelled frequency responses of a run, and its antiresonances.

    Attributes
    ----------
    theta, accel : FrequencyEstimate
        Ĥ1 of θ/v and a/v from the log (f > 0 only).
    model : ndarray of complex, shape (2, F)
        The model's θ/v and a/v at the same frequencies.
    antiresonances_model_hz, antiresonances_measured_hz : ndarray, shape (R,)
        The model's θ/v zeros (`station.plant.modal_summary`) and the measured notch of
        |Ĥ1 θ/v| nearest each (±25 %), Hz.
    n_elements : int
    """

    theta: FrequencyEstimate
    accel: FrequencyEstimate
    model: np.ndarray
    antiresonances_model_hz: np.ndarray
    antiresonances_measured_hz: np.ndarray
    n_elements: int

    @property
    def antiresonance_error_pct(self) -> np.ndarray:
        """100 (model − measured) / measured, per antiresonance."""
        return 100.0 * (self.antiresonances_model_hz - self.antiresonances_measured_hz) / self.antiresonances_measured_hz


def compare_bode(v, theta, a, dt: float, model, nperseg: int = 4096, max_hz: float = 40.0) -> BodeComparison:
    """H1 estimates of θ/v and a/v from a run, the model's response, antiresonances.

    Parameters
    ----------
    v, theta, a : array_like, shape (N,)
        The logged command (DAC counts), hub angle and accelerometer (counts); a
        swept-sine run excites the band (DESIGN.md: 0–40 Hz in 20 s).
    dt : float
        Sample time, s.
    model : station.plant.model.Model or station.plant.DiscretePlant
        The model: a Model's linear part (its param:NAME and beam_damping effects
        included) is sampled at ``dt``; a DiscretePlant is used as it is. Its parameters
        and element count give the antiresonances.
    nperseg : int, default 4096
        Welch segment length.
    max_hz : float, default 40
        Antiresonances of the model up to this frequency are compared.

    Returns
    -------
    BodeComparison

    Raises
    ------
    ValueError
        v or θ never changes (nothing drove the plant, or the hub never moved: θ/v is 0/0 or
        0 in every bin), or a run shorter than one segment.
    """
    for name, x, why in (("v", v, "nothing drove the plant"), ("θ", theta, "the hub never moved")):
        x = np.asarray(x, dtype=float)
        finite = x[np.isfinite(x)]
        if x.size and not (finite.size and np.ptp(finite) > 0):
            raise ValueError(f"{name} never changes (it holds {x[0]:g} throughout): {why}, there is no θ/v "
                             f"to estimate")
    plant = model if isinstance(model, DiscretePlant) else model.linear_plant(dt)
    est_theta = h1_estimate(v, theta, 1.0 / dt, nperseg)
    est_accel = h1_estimate(v, a, 1.0 / dt, nperseg)
    keep = est_theta.f > 0
    est_theta, est_accel = (FrequencyEstimate(e.f[keep], e.H[keep], e.coherence[keep]) for e in (est_theta, est_accel))
    model = model_response(plant, est_theta.f)
    zeros = modal_summary(plant.params, plant.n_elements, max_hz=max_hz).antiresonances_hz
    measured = notch_frequencies(est_theta.f, est_theta.H, zeros)
    return BodeComparison(est_theta, est_accel, model, zeros, measured, plant.n_elements)
