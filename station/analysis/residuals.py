"""Residual analysis of a model against a measured run, and the signatures a controls
engineer looks for in the residuals (DESIGN.md "Model diagnosis contract", issue 8).

- :func:`resid_test`: the whiteness and independence tests of MATLAB's ``resid``
  (L. Ljung, *System Identification*, 2nd ed., sec. 16.6): the normalized autocorrelation
  of the residual e and its cross-correlation with the input u, with the 99 % confidence
  band ±z/√N of a white residual independent of u.
- :func:`hub_sticking`: the hub stands still (θ constant) for many samples while the beam
  rings (|a| large): dry friction or backlash the linear model cannot show
  (:func:`sticking_spans`: where).
- :func:`steady_state_error`: the reference minus θ at the end of a closed-loop run.
- :func:`band_response`: amplitude ratio and phase lag of the measured signal against the
  model's per frequency band (Welch cross spectra, ``scipy.signal.csd``/``welch``).
- :func:`ringing_mode`: the frequency and decay rate of the strongest lightly damped mode
  in a signal (band-pass, Hilbert envelope, log-linear fit of the envelope).
- :func:`run_residuals`: all of the above for one run, measured vs model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.signal
import scipy.stats

from station.rig import DT, RATE_HZ

THETA_QUANTIZATION_STD = 1.0 / np.sqrt(12.0)
"""Standard deviation of the encoder's rounding error, counts (uniform on ±0.5)."""

ACCEL_NOISE_STD = 0.3
"""The accelerometer's noise, counts (DESIGN.md: 0.14-0.5 on the rig, 0.3 simulated)."""

BANDS_HZ = ((0.25, 2.0), (2.0, 4.0), (4.0, 12.0), (12.0, 25.0))
"""Frequency bands of :func:`band_response`, Hz: rigid-body, first mode (2.5 Hz), between,
second mode (18 Hz)."""


@dataclass(frozen=True)
class ResidTest:
    """MATLAB ``resid``-style tests of one residual.

    Attributes
    ----------
    lags : ndarray of int, shape (M+1,)
        0..M samples, for ``autocorr``.
    autocorr : ndarray, shape (M+1,)
        r_ee(τ)/r_ee(0), autocorr[0] = 1.
    cross_lags : ndarray of int, shape (2M+1,)
        -M..M samples; positive τ: the input leads the residual.
    crosscorr : ndarray, shape (2M+1,)
        r_eu(τ)/√(r_ee(0) r_uu(0)) with r_eu(τ) = (1/N) Σ e[k] u[k-τ].
    bound : float
        Half-width of the confidence band, z_{(1+c)/2}/√N.
    confidence : float
    white : bool
        All autocorr[1:] inside the band.
    independent : bool
        All crosscorr inside the band.
    """

    lags: np.ndarray
    autocorr: np.ndarray
    cross_lags: np.ndarray
    crosscorr: np.ndarray
    bound: float
    confidence: float

    @property
    def white(self) -> bool:
        return bool(np.all(np.abs(self.autocorr[1:]) <= self.bound))

    @property
    def independent(self) -> bool:
        return bool(np.all(np.abs(self.crosscorr) <= self.bound))

    @property
    def outside_pct(self) -> float:
        """Percent of the autocorrelation lags 1..M outside the band."""
        return float(100.0 * np.mean(np.abs(self.autocorr[1:]) > self.bound)) if self.autocorr.size > 1 else 0.0


def _xcorr(x: np.ndarray, y: np.ndarray, lag: int) -> float:
    """(1/N) Σ_k x[k] y[k - lag] (biased estimate, as ``resid``)."""
    n = x.size
    if lag >= 0:
        return float(np.dot(x[lag:], y[:n - lag]) / n)
    return float(np.dot(x[:n + lag], y[-lag:]) / n)


def resid_test(e, u, max_lag: int = 25, confidence: float = 0.99) -> ResidTest:
    """Autocorrelation of a residual and its cross-correlation with the input.

    Parameters
    ----------
    e : array_like, shape (N,)
        Residual (measured - model), e.g. θ in encoder counts.
    u : array_like, shape (N,)
        Input of the run (e.g. the command v, DAC counts).
    max_lag : int, default 25
        M, the largest lag, samples (``resid``'s default is 25).
    confidence : float, default 0.99
        Confidence level of the band.

    Returns
    -------
    ResidTest

    Raises
    ------
    ValueError
        Shapes differ, or N <= max_lag.

    Notes
    -----
    Both signals are made zero-mean first. A constant residual or input (zero variance)
    gives zero correlations. The band ±z/√N assumes a white residual (Ljung sec. 16.6),
    as MATLAB's ``resid`` draws it.
    """
    e = np.asarray(e, dtype=float).ravel()
    u = np.asarray(u, dtype=float).ravel()
    if e.shape != u.shape:
        raise ValueError(f"e and u must have the same shape, got {e.shape} and {u.shape}")
    n = e.size
    if n <= max_lag:
        raise ValueError(f"need more than max_lag = {max_lag} samples, got {n}")
    e = e - e.mean()
    u = u - u.mean()
    ree0 = _xcorr(e, e, 0)
    ruu0 = _xcorr(u, u, 0)
    lags = np.arange(max_lag + 1)
    cross_lags = np.arange(-max_lag, max_lag + 1)
    auto = np.array([_xcorr(e, e, k) for k in lags]) / ree0 if ree0 > 0 else np.zeros(lags.size)
    scale = np.sqrt(ree0 * ruu0)
    cross = np.array([_xcorr(e, u, k) for k in cross_lags]) / scale if scale > 0 else np.zeros(cross_lags.size)
    if ree0 > 0:
        auto[0] = 1.0
    z = float(scipy.stats.norm.ppf(0.5 + confidence / 2.0))
    return ResidTest(lags, auto, cross_lags, cross, z / np.sqrt(n), confidence)


def noise_std(x, floor: float = 0.0, fs: float = RATE_HZ, cutoff_hz: float = 60.0) -> float:
    """Robust noise level of a signal from its high-frequency part.

    The signal is high-passed (4th-order Butterworth above ``cutoff_hz``, zero phase) and
    its standard deviation estimated from the median absolute deviation (1.4826·MAD),
    corrected for the fraction of white noise's power the filter passes.

    Parameters
    ----------
    x : array_like, shape (N,)
        E.g. a model residual, counts.
    floor : float
        Returned when the estimate is lower (e.g. the quantization floor).
    fs, cutoff_hz : float
        Sample rate and high-pass corner, Hz.

    Returns
    -------
    float
        Noise standard deviation, units of x.
    """
    x = np.asarray(x, dtype=float).ravel()
    if x.size < 30 or not np.all(np.isfinite(x)):
        return float(floor)
    sos = scipy.signal.butter(4, cutoff_hz, "highpass", fs=fs, output="sos")
    hp = scipy.signal.sosfiltfilt(sos, x)
    passed = 1.0 - 2.0 * cutoff_hz / fs  # white noise power above the corner (ideal filter)
    mad = 1.4826 * np.median(np.abs(hp - np.median(hp)))
    return float(max(floor, mad / np.sqrt(passed)))


@dataclass(frozen=True)
class Sticking:
    """Intervals in which the hub stands still while the beam rings.

    Attributes
    ----------
    intervals : int
        Number of runs of ≥ ``min_samples`` samples with θ constant and max |a| above
        the threshold.
    duration_s : float
        Their total duration, s.
    max_abs_a : float
        Largest |a| inside them, counts (0 when none).
    """

    intervals: int
    duration_s: float
    max_abs_a: float


def sticking_spans(theta, a, min_samples: int = 25, a_threshold: float = 3.0) -> list[tuple[int, int]]:
    """Where θ is constant for many samples while |a| is large (:func:`hub_sticking`'s rule).

    Parameters
    ----------
    theta : array_like, shape (N,)
        Hub angle, encoder counts (whole counts).
    a : array_like, shape (N,)
        Tip acceleration, accelerometer counts.
    min_samples : int, default 25
        Shortest run of equal θ that counts.
    a_threshold : float, default 3.0
        The beam rings when max |a| over the run exceeds this, counts.

    Returns
    -------
    list of (int, int)
        Sample ranges [start, stop), in order.
    """
    theta = np.asarray(theta, dtype=float).ravel()
    a = np.asarray(a, dtype=float).ravel()
    n = theta.size
    if n == 0:
        return []
    change = np.flatnonzero(np.diff(theta) != 0) + 1
    starts = np.concatenate(([0], change))
    ends = np.concatenate((change, [n]))
    return [(int(s), int(e)) for s, e in zip(starts, ends)
            if e - s >= min_samples and float(np.max(np.abs(a[s:e]))) > a_threshold]


def hub_sticking(theta, a, dt: float = DT, min_samples: int = 25, a_threshold: float = 3.0) -> Sticking:
    """Find where θ is constant for many samples while |a| is large.

    Parameters
    ----------
    theta : array_like, shape (N,)
        Hub angle, encoder counts (whole counts).
    a : array_like, shape (N,)
        Tip acceleration, accelerometer counts.
    dt : float
        Sample time, s.
    min_samples : int, default 25
        Shortest run of equal θ that counts (25 samples = 50 ms).
    a_threshold : float, default 3.0
        The beam rings when max |a| over the run exceeds this, counts (10 σ of the
        accelerometer's noise).

    Returns
    -------
    Sticking
    """
    a = np.asarray(a, dtype=float).ravel()
    spans = sticking_spans(theta, a, min_samples, a_threshold)
    samples = sum(e - s for s, e in spans)
    peak = max((float(np.max(np.abs(a[s:e]))) for s, e in spans), default=0.0)
    return Sticking(len(spans), float(samples * dt), peak)


def steady_state_error(theta, u, tail: float = 0.2) -> float:
    """Mean of u − θ over the last ``tail`` fraction of a run, encoder counts.

    Parameters
    ----------
    theta, u : array_like, shape (N,)
        Logged θ and reference, encoder counts.
    tail : float, default 0.2
        Fraction of the run at its end that is averaged.
    """
    theta = np.asarray(theta, dtype=float).ravel()
    u = np.asarray(u, dtype=float).ravel()
    k = max(1, int(round(tail * theta.size)))
    return float(np.mean(u[-k:] - theta[-k:]))


@dataclass(frozen=True)
class BandResponse:
    """Measured signal against the model's in one frequency band.

    Attributes
    ----------
    band_hz : tuple of float
    amplitude_ratio : float
        |P_ŷy|/P_ŷŷ averaged over the band: measured amplitude per model amplitude.
    phase_lag_deg : float
        −angle of P_ŷy/P_ŷŷ: positive when the measured signal lags the model's.
    coherence : float
        Mean magnitude-squared coherence of model and measurement in the band.
    """

    band_hz: tuple
    amplitude_ratio: float
    phase_lag_deg: float
    coherence: float


def band_response(measured, model, fs: float = RATE_HZ, bands=BANDS_HZ) -> list[BandResponse]:
    """Amplitude ratio and phase lag of a measured signal against the model's, per band.

    The ratio H(f) = P_ŷy(f)/P_ŷŷ(f) (Welch cross spectrum of model output ŷ and
    measurement y over the model's auto spectrum, ``scipy.signal.csd``/``welch``, Hann
    segments of up to 512 samples) is the transfer from the model's signal to the
    measured one; in each band it is averaged weighted by P_ŷŷ (where the model has
    power).

    Parameters
    ----------
    measured, model : array_like, shape (N,)
        Same units (e.g. θ in encoder counts).
    fs : float
        Sample rate, Hz.
    bands : sequence of (f_lo, f_hi)
        Hz.

    Returns
    -------
    list of BandResponse
        One per band that holds at least one frequency and model power; NaN fields where
        the model has no power.
    """
    y = np.asarray(measured, dtype=float).ravel()
    yh = np.asarray(model, dtype=float).ravel()
    nper = int(min(512, y.size))
    f, pxy = scipy.signal.csd(yh, y, fs=fs, nperseg=nper, detrend="constant")
    _, pxx = scipy.signal.welch(yh, fs=fs, nperseg=nper, detrend="constant")
    _, pyy = scipy.signal.welch(y, fs=fs, nperseg=nper, detrend="constant")
    out = []
    for lo, hi in bands:
        sel = (f >= lo) & (f < hi)
        w = pxx[sel]
        if not np.any(sel) or w.sum() <= 0:
            out.append(BandResponse((lo, hi), float("nan"), float("nan"), float("nan")))
            continue
        h = np.sum(pxy[sel]) / np.sum(w)
        coh = np.abs(pxy[sel]) ** 2 / np.maximum(pxx[sel] * pyy[sel], 1e-300)
        out.append(BandResponse((lo, hi), float(np.abs(h)), float(-np.degrees(np.angle(h))), float(np.mean(coh))))
    return out


@dataclass(frozen=True)
class Mode:
    """The strongest lightly damped oscillation in a signal.

    Attributes
    ----------
    frequency_hz : float
    decay_per_s : float
        σ in exp(−σ t) of the envelope, 1/s (ζ ≈ σ/(2π f)).
    """

    frequency_hz: float
    decay_per_s: float

    @property
    def damping_ratio(self) -> float:
        return float(self.decay_per_s / (2 * np.pi * self.frequency_hz)) if self.frequency_hz > 0 else float("nan")


def ringing_mode(x, fs: float = RATE_HZ, band_hz: tuple = (1.0, 6.0), start: int = 0) -> Mode | None:
    """Frequency and decay rate of the strongest oscillation of x in a band.

    The frequency is the Welch spectral peak in ``band_hz`` (refined by parabolic
    interpolation); the decay rate is the slope of a least-squares line through the log
    of the Hilbert envelope of x band-passed ±40 % around it, from ``start`` to where the
    envelope falls to 10 % of its peak (edges trimmed).

    Parameters
    ----------
    x : array_like, shape (N,)
        E.g. tip acceleration, counts.
    fs : float
        Sample rate, Hz.
    band_hz : (f_lo, f_hi)
        Where to look, Hz (default: the first beam mode, 2.5 Hz).
    start : int
        First sample of the free ringing (e.g. after the last command change).

    Returns
    -------
    Mode or None
        None when the signal is too short or has no power in the band.
    """
    x = np.asarray(x, dtype=float).ravel()[start:]
    if x.size < int(fs / band_hz[0]) or np.ptp(x) == 0:
        return None
    x = x - x.mean()
    nper = int(min(x.size, 4 * fs / band_hz[0]))
    f, p = scipy.signal.welch(x, fs=fs, nperseg=nper, nfft=max(nper, 4096))
    sel = np.flatnonzero((f >= band_hz[0]) & (f <= band_hz[1]))
    if sel.size == 0 or p[sel].max() <= 0:
        return None
    i = sel[np.argmax(p[sel])]
    fpk = f[i]
    if 0 < i < f.size - 1:
        a, b, c = np.log(p[i - 1:i + 2] + 1e-300)
        den = a - 2 * b + c
        delta = 0.5 * (a - c) / den if den < 0 else 0.0  # a true peak only: within half a bin
        if abs(delta) <= 0.5:  # (noise alone, a flat spectrum, sent it below 0 Hz: issue 17)
            fpk = f[i] + delta * (f[1] - f[0])
    sos = scipy.signal.butter(2, (0.6 * fpk, min(1.4 * fpk, 0.45 * fs)), "bandpass", fs=fs, output="sos")
    env = np.abs(scipy.signal.hilbert(scipy.signal.sosfiltfilt(sos, x)))
    trim = int(fs / fpk)  # one period at each end: filter and Hilbert edge effects
    env = env[trim:env.size - trim]
    if env.size < 3 * trim or env.max() <= 0:
        return Mode(float(fpk), float("nan"))
    k0 = int(np.argmax(env))
    tail = env[k0:]
    below = np.flatnonzero(tail < 0.1 * tail[0])
    tail = tail[:below[0]] if below.size else tail
    if tail.size < max(10, trim // 4):
        return Mode(float(fpk), float("nan"))
    slope = np.polyfit(np.arange(tail.size) / fs, np.log(tail), 1)[0]
    return Mode(float(fpk), float(-slope))


@dataclass(frozen=True)
class RunResiduals:
    """A model against one measured run: tests and signatures, measured next to model.

    Attributes
    ----------
    theta, accel : ResidTest
        ``resid`` tests of the θ and a residuals against the command v.
    rms_theta, rms_accel : float
        RMS of the residuals, counts.
    sticking_measured, sticking_model : Sticking
    sse_measured, sse_model : float or None
        Steady-state error u − θ (closed loop), encoder counts.
    theta_bands, accel_bands : list of BandResponse
        Measured against model per band (amplitude ratio, phase lag).
    mode_measured, mode_model : Mode or None
        The first beam mode seen in a, after the last change of the command.
    """

    theta: ResidTest
    accel: ResidTest
    rms_theta: float
    rms_accel: float
    sticking_measured: Sticking
    sticking_model: Sticking
    sse_measured: float | None
    sse_model: float | None
    theta_bands: list
    accel_bands: list
    mode_measured: Mode | None
    mode_model: Mode | None

    def signatures(self) -> list[str]:
        """The notable differences, one short sentence each (for evidence and reports)."""
        out = []
        sm, sn = self.sticking_measured, self.sticking_model
        if sm.duration_s > sn.duration_s + 0.05:
            out.append(f"the hub sticks {sm.duration_s:.2f} s while the beam rings (|a| up to {sm.max_abs_a:.0f}), "
                       f"the model {sn.duration_s:.2f} s")
        if self.sse_measured is not None and self.sse_model is not None \
                and abs(self.sse_measured - self.sse_model) >= 1.0:
            out.append(f"steady-state error {self.sse_measured:.1f} counts, model {self.sse_model:.1f}")
        for b in self.theta_bands:
            if np.isfinite(b.amplitude_ratio) and b.coherence > 0.5 and \
                    (abs(np.log(b.amplitude_ratio)) > np.log(1.25) or abs(b.phase_lag_deg) > 20):
                out.append(f"θ at {b.band_hz[0]:g}-{b.band_hz[1]:g} Hz: {b.amplitude_ratio:.2f}× the model's, "
                           f"lagging {b.phase_lag_deg:.0f}°")
        mm, mo = self.mode_measured, self.mode_model
        if mm is not None and mo is not None:
            if abs(mm.frequency_hz - mo.frequency_hz) > 0.05 * mo.frequency_hz:
                out.append(f"first mode at {mm.frequency_hz:.2f} Hz, model {mo.frequency_hz:.2f} Hz")
            if np.isfinite(mm.decay_per_s) and np.isfinite(mo.decay_per_s) and \
                    abs(mm.decay_per_s - mo.decay_per_s) > 0.25 * max(mo.decay_per_s, 0.2):
                out.append(f"first mode decays at {mm.decay_per_s:.2f}/s, model {mo.decay_per_s:.2f}/s")
        if not self.theta.white:
            out.append(f"θ residual not white ({self.theta.outside_pct:.0f} % of lags outside the 99 % band)")
        return out


def run_residuals(theta, a, theta_model, a_model, v, u=None, closed: bool = True,
                  dt: float = DT, max_lag: int = 25) -> RunResiduals:
    """Residual tests and signatures of a model's run against the measured one.

    Parameters
    ----------
    theta, a : array_like, shape (N,)
        Measured θ (encoder counts) and a (accelerometer counts).
    theta_model, a_model : array_like, shape (N,)
        The model's, same units.
    v : array_like, shape (N,)
        The logged command (the input of the residual tests), DAC counts.
    u : array_like, shape (N,), optional
        The reference (closed loop: for the steady-state error).
    closed : bool
        Closed-loop run (steady-state error defined).
    dt : float
        Sample time, s.
    max_lag : int
        Of the ``resid`` tests.

    Returns
    -------
    RunResiduals
    """
    theta, a = np.asarray(theta, float), np.asarray(a, float)
    theta_model, a_model = np.asarray(theta_model, float), np.asarray(a_model, float)
    v = np.asarray(v, float)
    fs = 1.0 / dt
    et, ea = theta - theta_model, a - a_model
    # free ringing after the last big change of the command (a step's transient or a pulse's end)
    big = np.flatnonzero(np.abs(np.diff(v)) > 0.2 * max(float(np.ptp(v)), 1e-9)) if v.size > 1 else np.array([])
    start = int(big[-1] + 1) if big.size else 0
    sse_m = sse_n = None
    if closed and u is not None:
        sse_m = steady_state_error(theta, u)
        sse_n = steady_state_error(theta_model, u)
    return RunResiduals(
        theta=resid_test(et, v, max_lag), accel=resid_test(ea, v, max_lag),
        rms_theta=float(np.sqrt(np.mean(et ** 2))), rms_accel=float(np.sqrt(np.mean(ea ** 2))),
        sticking_measured=hub_sticking(theta, a, dt), sticking_model=hub_sticking(theta_model, a_model, dt),
        sse_measured=sse_m, sse_model=sse_n,
        theta_bands=band_response(theta, theta_model, fs), accel_bands=band_response(a, a_model, fs),
        mode_measured=ringing_mode(a, fs, start=start), mode_model=ringing_mode(a_model, fs, start=start),
    )
