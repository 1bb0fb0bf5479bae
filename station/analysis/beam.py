"""Hub-held beam tests: the first mode's frequency and damping from the free vibration.

The rig's hold-and-release, ping and stab tests hold the hub still (motor unpowered or
blocked; the logged v is not applied) and excite the beam by hand. What they measure is
the beam's free vibration after the release, seen by the tip accelerometer: a decaying
sinusoid at the first hub-held mode (DESIGN.md: 2.52 Hz, ζ ≈ 0.005). The motor model
driven by the logged v cannot represent such a test, so replay analyzes it here instead.

Method: a band-pass of a (Butterworth, 1-5 Hz, zero phase: scipy.signal.butter +
sosfiltfilt) keeps the first mode; from 0.5 s after the release (the largest |a|) to
the end of the log, a damped sine A·exp(-ζω_n t)·sin(ω_d t + φ) is fitted by
scipy.optimize.least_squares, and cross-checked by the log decrement of the successive
peaks. Standard errors: from the fit's Jacobian, with the residual variance counted on
the effective number of independent samples of band-limited noise (N·2B/fs, B the pass
band), and from the regressions of the peaks (scipy.stats.linregress).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

HELD_COUNTS = 8.0
"""A run is hub-held when theta stays within this many encoder counts ..."""

HELD_MIN_V = 50.0
"""... while |v| >= this many DAC counts ..."""

HELD_MIN_S = 1.0
"""... for at least this long, s."""

BAND_HZ = (1.0, 5.0)
"""Pass band of the first-mode analysis, Hz."""

SKIP_S = 0.5
"""The fit starts this long after the release, s (the hand has let go; higher modes died)."""

END_GUARD_S = 1.0
"""The log decrement ignores the last second of the record (filter transient), s."""

MIN_CYCLES = 3.0
"""Fewer cycles than this after the skip: frequency and damping not measurable."""

FREE_MODE_TOLERANCE = 0.10
"""A measured first mode further than this fraction from the model's hub-held first mode is
not the free beam's (:attr:`BeamTestReport.free_first_mode`): the lab's pings and stabs with
an eraser held at mid-span ring at 2.84-3.49 Hz with ζ 0.04-0.08, where the beam released
free rings at 2.516-2.526 Hz beside the model's 2.550 (within 1.4 %)."""


@dataclass(frozen=True)
class HubHeld:
    """Evidence that a run held the hub (:func:`hub_held`).

    Attributes
    ----------
    duration_s : float
        Longest stretch with |v| >= HELD_MIN_V, s.
    theta_span : float
        max θ - min θ over it, encoder counts.
    v : float
        max |v| over it, DAC counts.
    """

    duration_s: float
    theta_span: float
    v: float


@dataclass(frozen=True)
class BeamTest:
    """First mode of a hub-held beam test (:func:`analyze_beam_test`).

    Attributes
    ----------
    f1_hz, f1_hz_std : float or None
        Damped frequency of the first mode from the damped-sine fit, Hz, and its
        standard error (None: not measurable).
    zeta1, zeta1_std : float or None
        Its damping ratio and standard error, 1.
    f1_logdec_hz, f1_logdec_hz_std, zeta1_logdec, zeta1_logdec_std : float or None
        The same from the peaks' log decrement (cross-check).
    release_s : float or None
        Time of the release (largest |a - median a|), s.
    fit_start_s : float or None
        Start of the analyzed window, s.
    cycles : float
        Cycles of the first mode in the window.
    notes : tuple of str
        What could not be measured, or where the two estimates disagree.
    """

    f1_hz: float | None
    f1_hz_std: float | None
    zeta1: float | None
    zeta1_std: float | None
    f1_logdec_hz: float | None = None
    f1_logdec_hz_std: float | None = None
    zeta1_logdec: float | None = None
    zeta1_logdec_std: float | None = None
    release_s: float | None = None
    fit_start_s: float | None = None
    cycles: float = 0.0
    notes: tuple[str, ...] = ()


def hub_held(theta, v, dt: float) -> HubHeld | None:
    """Whether a run held the hub: θ within :data:`HELD_COUNTS` counts while
    |v| >= :data:`HELD_MIN_V` for at least :data:`HELD_MIN_S` s.

    Parameters
    ----------
    theta, v : array_like, shape (N,)
        Logged encoder counts and commands (DAC counts).
    dt : float
        Sample time, s.

    Returns
    -------
    HubHeld or None
        The longest such stretch, or None when the run is not hub-held (a powered motor
        moves far with |v| >= 50 held for a second).
    """
    theta = np.asarray(theta, dtype=float)
    v = np.asarray(v, dtype=float)
    if theta.size == 0 or not np.all(np.isfinite(v)) or not np.all(np.isfinite(theta)):
        return None
    big = np.abs(v) >= HELD_MIN_V
    edges = np.flatnonzero(np.diff(np.concatenate(([0], big.astype(np.int8), [0]))))
    best = None
    for start, stop in zip(edges[::2], edges[1::2]):
        duration = (stop - start) * dt
        if duration < HELD_MIN_S:
            continue
        span = float(np.ptp(theta[start:stop]))
        if span <= HELD_COUNTS and (best is None or duration > best.duration_s):
            best = HubHeld(float(duration), span, float(np.max(np.abs(v[start:stop]))))
    return best


def band_pass(x, dt: float, band: tuple[float, float] = BAND_HZ, order: int = 4) -> np.ndarray:
    """Zero-phase Butterworth band-pass (scipy.signal.butter, sosfiltfilt).

    Parameters
    ----------
    x : array_like, shape (N,)
    dt : float
        Sample time, s.
    band : (float, float)
        Pass band edges, Hz (below Nyquist).
    order : int
        Order of the low-pass prototype.

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    # lazy: start-up time (scipy.signal: station.logged imports this module for hub_held)
    from scipy.signal import butter, sosfiltfilt

    sos = butter(order, band, btype="bandpass", fs=1.0 / dt, output="sos")
    return sosfiltfilt(sos, np.asarray(x, dtype=float))


def _damped_sine(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    amp, f, zeta, phase = p
    wd = 2 * math.pi * f
    wn = wd / math.sqrt(max(1.0 - zeta * zeta, 1e-12))
    return amp * np.exp(-zeta * wn * t) * np.sin(wd * t + phase)


def _peaks(y: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times and values of the positive maxima, refined by a parabola through each."""
    from scipy.signal import find_peaks  # lazy: start-up time (scipy.signal)

    idx, _ = find_peaks(y)
    idx = idx[(idx > 0) & (idx < y.size - 1) & (y[idx] > 0)]
    y0, y1, y2 = y[idx - 1], y[idx], y[idx + 1]
    den = y0 - 2 * y1 + y2
    off = np.where(den != 0, 0.5 * (y0 - y2) / np.where(den != 0, den, 1.0), 0.0)
    dt = t[1] - t[0]
    return t[idx] + off * dt, y1 - 0.25 * (y0 - y2) * off


def _log_decrement(y: np.ndarray, t: np.ndarray, floor: float) -> tuple[float, float, float, float] | None:
    """(f, f_std, zeta, zeta_std) from the peaks above ``floor``, or None."""
    from scipy.stats import linregress  # lazy: start-up time (scipy.stats)

    tp, yp = _peaks(y, t)
    keep = yp > floor
    # peaks are one period apart: drop spurious ones (noise ripples) by their spacing
    tp, yp = tp[keep], yp[keep]
    if tp.size < 4:
        return None
    period = float(np.median(np.diff(tp)))
    cycles = np.round((tp - tp[0]) / period)
    uniq = np.concatenate(([True], np.diff(cycles) > 0))
    tp, yp, cycles = tp[uniq], yp[uniq], cycles[uniq]
    if tp.size < 4:
        return None
    per = linregress(cycles, tp)
    dec = linregress(cycles, np.log(yp))
    delta, delta_std = -dec.slope, dec.stderr
    f = 1.0 / per.slope
    f_std = per.stderr / per.slope ** 2
    zeta = delta / math.sqrt(4 * math.pi ** 2 + delta ** 2)
    zeta_std = delta_std * 4 * math.pi ** 2 / (4 * math.pi ** 2 + delta ** 2) ** 1.5
    return f, f_std, zeta, zeta_std


def analyze_beam_test(t, a, dt: float, band: tuple[float, float] = BAND_HZ) -> BeamTest:
    """First-mode frequency and damping ratio of a hub-held beam test's free vibration.

    Parameters
    ----------
    t : array_like, shape (N,)
        Time, s (evenly spaced by ``dt``).
    a : array_like, shape (N,)
        Tip accelerometer, ADC counts (any offset; a baseline that drifts, or jumps at a
        strike and creeps back, is removed: before the release its median, after it a cubic
        trend).
    dt : float
        Sample time, s.
    band : (float, float)
        Pass band that isolates the first mode, Hz (default 1-5 Hz).

    Returns
    -------
    BeamTest
        Fields None (with a note) where the window after the release is too short, a
        carries no vibration, or the fit does not converge.

    Notes
    -----
    The damped-sine model's frequency is the damped one, f_d = f_n·sqrt(1 - ζ²) (what
    the model's hub-held poles' imaginary parts give too). Log decrement:
    δ = ln(x_k / x_{k+1}) from a straight-line fit of ln(peak) over the cycle number,
    ζ = δ / sqrt(4π² + δ²) (e.g. Inman, Engineering Vibration, sec. 1.6).
    """
    from scipy.optimize import least_squares  # lazy: start-up time (scipy.optimize)

    t = np.asarray(t, dtype=float)
    a = np.asarray(a, dtype=float)
    notes: list[str] = []
    if a.size < 16 or not np.all(np.isfinite(a)):
        return BeamTest(None, None, None, None, notes=("a is missing or holds non-numbers: no beam analysis",))
    if not (0 < band[0] < band[1] < 0.5 / dt):
        return BeamTest(None, None, None, None,
                        notes=(f"the {band[0]:g}-{band[1]:g} Hz band does not fit below the Nyquist frequency",))
    # The release (or strike) is the largest jump between two samples: a baseline that is not
    # zeroed or drifts (a stab) moves slowly. Before it a is centred on its median; after it
    # on a cubic trend: an accelerometer's baseline that jumps at a strike and creeps back
    # leaves the band-pass no step to ring on, and no cubic over seconds follows the mode.
    release = int(np.argmax(np.abs(np.diff(a)))) + 1 if a.size > 1 else 0
    centered = np.empty_like(a)
    centered[:release] = a[:release] - (np.median(a[:release]) if release else 0.0)
    tail = t[release:] - t[release]
    trend = np.polyval(np.polyfit(tail, a[release:], min(3, max(tail.size - 1, 0))), tail) if tail.size else tail
    centered[release:] = a[release:] - trend
    start = release + int(round(SKIP_S / dt))
    y_all = band_pass(centered, dt, band)
    y, tw = y_all[start:], t[start:] - t[start] if start < t.size else t[:0]
    duration = tw.size * dt
    base = dict(release_s=float(t[release]), fit_start_s=float(t[start]) if start < t.size else None)
    if y.size < 16 or np.ptp(y) == 0:
        return BeamTest(None, None, None, None, notes=("no free vibration after the release",), **base)

    # Starting values: FFT peak (zero-padded), log decrement, the first peak.
    nfft = 1 << int(math.ceil(math.log2(max(y.size * 8, 1024))))
    spec = np.abs(np.fft.rfft(y * np.hanning(y.size), nfft))
    freqs = np.fft.rfftfreq(nfft, dt)
    inband = (freqs >= band[0]) & (freqs <= band[1])
    f0 = float(freqs[inband][np.argmax(spec[inband])])
    cycles = duration * f0
    if cycles < MIN_CYCLES:
        return BeamTest(None, None, None, None, cycles=float(cycles),
                        notes=(f"only {cycles:.1f} cycles of vibration after the release + {SKIP_S:g} s "
                               f"(need {MIN_CYCLES:g}): first mode not measurable",), **base)
    zeta0 = 0.01
    amp0 = float(np.max(np.abs(y[: max(int(1.0 / (f0 * dt)), 2)])))
    best = None
    best_bounds = ([0.0, band[0], 0.0, -4 * math.pi], [np.inf, band[1], 0.9, 4 * math.pi])
    best_scale = [amp0 or 1.0, 0.1, 0.005, 1.0]
    for phase0 in (0.0, math.pi / 2, math.pi, 3 * math.pi / 2):
        res = least_squares(lambda p: _damped_sine(p, tw) - y, [amp0, f0, zeta0, phase0],
                            bounds=best_bounds, x_scale=best_scale, method="trf")
        if best is None or res.cost < best.cost:
            best = res
    if best is not None and best.success:
        # Refine with the model passed through the same filter from the release on: the
        # filter's own transients (release, end of the record) then bias nothing.
        t_model = t[release:] - t[start]
        full = np.zeros(a.size)

        def filtered_residual(p: np.ndarray) -> np.ndarray:
            full[release:] = _damped_sine(p, t_model)
            return band_pass(full, dt, band)[start:] - y

        refined = least_squares(filtered_residual, best.x, bounds=best_bounds, x_scale=best_scale, method="trf")
        if refined.success:
            best = refined
    f1 = zeta1 = f1_std = zeta1_std = None
    if best is not None and best.success:
        amp, f1, zeta1, _ = (float(x) for x in best.x)
        dof = y.size - 4
        # Band-limited noise: N samples hold only about N·2B/fs independent ones.
        n_eff = max(y.size * 2 * (band[1] - band[0]) * dt, 5.0)
        s2 = 2 * best.cost / dof * (y.size / n_eff)
        try:
            cov = np.linalg.inv(best.jac.T @ best.jac) * s2
            f1_std, zeta1_std = (float(math.sqrt(max(cov[i, i], 0.0))) for i in (1, 2))
        except np.linalg.LinAlgError:
            notes.append("the fit's Jacobian is singular: no standard errors")
    else:
        notes.append("the damped-sine fit did not converge")
    out = BeamTest(f1, f1_std, zeta1, zeta1_std, cycles=float(cycles), **base)
    # Log decrement on the peaks above the noise (3x the fit's residual RMS), away from the
    # end of the record where the zero-phase filter's start-up transient sits.
    noise = math.sqrt(2 * best.cost / y.size) if best is not None else 0.0
    edge = tw < tw[-1] - END_GUARD_S
    logdec = _log_decrement(y[edge], tw[edge], floor=3.0 * noise) if edge.sum() > 16 else None
    if logdec is not None:
        fl, fl_std, zl, zl_std = (float(x) for x in logdec)
        out = BeamTest(f1, f1_std, zeta1, zeta1_std, fl, fl_std, zl, zl_std, cycles=float(cycles), **base)
        if f1 is not None and zeta1 is not None:
            if abs(fl - f1) > 0.03 * f1:
                notes.append(f"log decrement gives {fl:.3f} Hz, the damped-sine fit {f1:.3f} Hz")
            if abs(zl - zeta1) > 0.3 * max(zeta1, 1e-3):
                notes.append(f"log decrement gives zeta {zl:.4f}, the damped-sine fit {zeta1:.4f}")
    else:
        notes.append("too few clear peaks for the log-decrement cross-check")
    return BeamTest(**{**out.__dict__, "notes": tuple(notes)})


def model_first_mode(model=None, n_elements: int = 4) -> tuple[float, float]:
    """The model's first hub-held (base held) beam mode: damped frequency, Hz, and ζ.

    Parameters
    ----------
    model : station.plant.model.Model, station.plant.Params or None
        None: the nominal tmm-fit parameter set. A Model's ``beam_damping`` effect, when
        it has one, sets the first-mode ζ (DESIGN.md effect vocabulary).
    n_elements : int
        Element count (a Model's own wins).

    Returns
    -------
    (float, float)
        From :func:`station.plant.modes.modal_summary` (the θ/v antiresonance, i.e. the
        base-held mode); tmm-fit, 4 elements: 2.55 Hz, ζ 0.0054.
    """
    # lazy: start-up time (the FEM: station.logged imports this module for hub_held)
    from station.plant import load_params
    from station.plant.modes import modal_summary, with_beam_damping

    params = model
    effects = {}
    if model is None:
        params = load_params("tmm-fit")
    elif hasattr(model, "params") and hasattr(model, "effect_dict"):
        params, n_elements, effects = model.params, model.n_elements, model.effect_dict()
    zeta = effects.get("beam_damping")
    if zeta is not None:
        params = with_beam_damping(params, float(zeta), n_elements)
    ms = modal_summary(params, n_elements)
    return float(ms.antiresonances_hz[0]), float(ms.antiresonance_damping[0])


@dataclass(frozen=True)
class BeamTestReport:
    """A hub-held beam test next to the model's hub-held first mode (replay's ``beam_test``).

    Attributes
    ----------
    measured : BeamTest
    held : HubHeld
        Why the run counts as hub-held.
    f1_model_hz, zeta1_model : float or None
        The model's first hub-held mode (:func:`model_first_mode`), Hz and 1.
    """

    measured: BeamTest
    held: HubHeld
    f1_model_hz: float | None
    zeta1_model: float | None

    @property
    def f1_off_model_pct(self) -> float | None:
        """The measured first mode's departure from the model's, % (None: either missing)."""
        f, fm = self.measured.f1_hz, self.f1_model_hz
        return None if f is None or not fm else 100.0 * (f / fm - 1.0)

    @property
    def free_first_mode(self) -> bool | None:
        """Whether the mode measured is the free beam's first mode as the model holds it:
        within :data:`FREE_MODE_TOLERANCE` of the model's frequency (None: not decidable)."""
        off = self.f1_off_model_pct
        return None if off is None else abs(off) <= 100.0 * FREE_MODE_TOLERANCE

    def departure(self) -> str | None:
        """One line when the mode measured is not the free beam's first mode, else None."""
        if self.free_first_mode is not False:
            return None
        m, off = self.measured, self.f1_off_model_pct
        zeta = ("" if m.zeta1 is None or not self.zeta1_model else
                f" and ζ {m.zeta1:.3f}, {m.zeta1 / self.zeta1_model:.0f}× its {self.zeta1_model:.4f}")
        return (f"the 1-5 Hz band rings at {m.f1_hz:.3f} Hz, {abs(off):.0f} % {'above' if off > 0 else 'below'} the "
                f"model's hub-held first mode ({self.f1_model_hz:.3f} Hz){zeta}: not the free beam's first mode "
                f"(touched, held or changed during the test)")

    def to_json(self) -> dict:
        """``{"f1_hz", "f1_hz_std", "zeta1", "zeta1_std", "f1_model_hz", "zeta1_model",
        "f1_off_model_pct", "free_first_mode"}`` (null where not measurable) plus the log-decrement cross-check, the release and
        window times, and what made the run hub-held."""
        m = self.measured
        return {"f1_hz": m.f1_hz, "f1_hz_std": m.f1_hz_std, "zeta1": m.zeta1, "zeta1_std": m.zeta1_std,
                "f1_model_hz": self.f1_model_hz, "zeta1_model": self.zeta1_model,
                "f1_off_model_pct": self.f1_off_model_pct, "free_first_mode": self.free_first_mode,
                "logdec": {"f1_hz": m.f1_logdec_hz, "f1_hz_std": m.f1_logdec_hz_std,
                           "zeta1": m.zeta1_logdec, "zeta1_std": m.zeta1_logdec_std},
                "release_s": m.release_s, "fit_start_s": m.fit_start_s, "cycles": m.cycles,
                "hub_held": {"duration_s": self.held.duration_s, "theta_span_counts": self.held.theta_span,
                             "v_counts": self.held.v},
                "notes": list(m.notes)}
