"""The loop's linear part: stability margins and closed-loop poles of a compensator on a model.

The station's loop (DESIGN.md "Timing and log rows", alignment d = 1 on protocol v1 and the
simulated rig) computes v[k] = Gth(S(u) − Ga(a) − θ) from θ[k−d], a[k−d]; a model's extra
amplifier delay D and accelerometer gain act on the linear part too. Broken at the plant's
input, the loop transfer function is

    L(z) = z^−(d+D) · Gth(z) · (Pθ(z) + accel_gain · Ga(z) · Pa(z))

with Pθ, Pa the sampled (exact ZOH) plant from v to θ and a (the model's linear part:
friction, saturation, dead-zone and offsets left out), negative feedback. The shaper is
outside the loop.

- :func:`margins`: gain and phase margins of L, python-control's ``stability_margins``
  (the reported values, :meth:`LoopModel.margins_control`) or the same crossings found on
  the same frequency grid with numpy (:meth:`LoopModel.margins`, what the search uses:
  python-control's FRD interpolation costs ~0.2 s per call, the search makes thousands;
  tests/test_tune_linear.py shows both agree).
- :meth:`LoopModel.spectral_radius`: the largest closed-loop pole magnitude, from the
  closed loop's state matrix (< 1: stable; margins mean nothing without it).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
import scipy.signal

from station.rig import DT

ALIGNMENT = 1
"""The computational delay of the station's loop on protocol v1 and the simulated rig, samples."""

GRID_POINTS = 4000
"""Log-spaced frequencies of the margin grid, 0.5 rad/s to just below Nyquist."""


class Margins(NamedTuple):
    """The loop's stability margins (the worst crossing of each kind).

    Attributes
    ----------
    gain_margin_db : float
        The smallest |20 log10 GM| over the phase crossovers (L on the negative real axis),
        dB; inf with none. A lower gain margin (GM < 1) counts by its size too.
    phase_margin_deg : float
        The smallest 180° − |∠L| over the gain crossovers (|L| = 1), degrees; inf with none.
    crossover_rad_s : float
        The highest gain-crossover frequency, rad/s (NaN with none).
    """

    gain_margin_db: float
    phase_margin_deg: float
    crossover_rad_s: float


def _tf_z(num, den):
    """Descending-power z coefficients of equal length from ascending z⁻¹ lists."""
    num, den = list(map(float, num)), list(map(float, den))
    m = max(len(num), len(den))
    return np.array(num + [0.0] * (m - len(num))), np.array(den + [0.0] * (m - len(den)))


def _freq(tf, zinv: np.ndarray) -> np.ndarray:
    """A DiscreteTF's response at z⁻¹ values."""
    if tf is None:
        return np.zeros_like(zinv)
    return np.polyval(np.asarray(tf.num)[::-1], zinv) / np.polyval(np.asarray(tf.den)[::-1], zinv)


class LoopModel:
    """A model's linear part, ready for loop checks of many compensators (cached per model).

    Parameters
    ----------
    model : station.plant.model.Model
        Its linear part (``linear_plant``), extra ``delay`` and ``accel_gain``.
    dt : float
        Sample time, s.
    alignment : int
        The loop's computational delay d, samples.

    Attributes
    ----------
    omega : ndarray, shape (W,)
        The frequency grid, rad/s.
    p_theta, p_accel : ndarray of complex, shape (W,)
        Pθ and Pa (times accel_gain) on it, counts per DAC count.
    """

    def __init__(self, model, dt: float = DT, alignment: int = ALIGNMENT):
        plant = model.linear_plant(dt)
        self.dt = float(dt)
        self.delay = int(alignment) + int(model.effect("delay"))
        self.accel_gain = float(model.effect("accel_gain"))
        self._A, self._B, self._C = plant.Ad, plant.Bd, plant.Cd
        self._d = int(alignment)
        lam, vec = np.linalg.eig(self._A)
        self.omega = _grid(lam, self.dt)
        z = np.exp(1j * self.omega * self.dt)
        # modal form: P(z) = C V diag(1/(z - λ)) V⁻¹ B
        left = self._C @ vec
        right = np.linalg.solve(vec, self._B.astype(complex))
        resp = (left[:, None, :] * (right[None, None, :] / (z[None, :, None] - lam[None, None, :]))).sum(axis=2)
        self.p_theta = resp[0]
        self.p_accel = resp[1] * self.accel_gain
        self._zinv = 1.0 / z

    def loop(self, compensator) -> np.ndarray:
        """L(e^{jωT}) on :attr:`omega` for a compensator.

        Parameters
        ----------
        compensator : station.control.Compensator
            Its ``gth`` and ``ga`` (DiscreteTF, z⁻¹; ``ga`` may be None).

        Returns
        -------
        ndarray of complex, shape (W,)
            The loop transfer function L = z^-delay Gth (Pθ + Ga Pa) at each frequency of
            :attr:`omega`, dimensionless (counts per count).
        """
        zinv = self._zinv
        inner = self.p_theta + (_freq(compensator.ga, zinv) * self.p_accel if compensator.ga is not None else 0.0)
        return zinv ** self.delay * _freq(compensator.gth, zinv) * inner

    def margins(self, compensator) -> Margins:
        """Gain and phase margins of L from its crossings on the grid (linear interpolation).

        Parameters
        ----------
        compensator : station.control.Compensator

        Returns
        -------
        Margins
            Gain margin (dB), phase margin (degrees), highest gain crossover (rad/s); inf/NaN
            where L has no crossing of that kind on the grid.
        """
        return grid_margins(self.loop(compensator), self.omega)

    def margins_control(self, compensator) -> Margins:
        """The same margins by python-control's ``stability_margins`` on L's frequency response
        (an FRD on :attr:`omega`, discrete at dt), all crossings.

        Parameters
        ----------
        compensator : station.control.Compensator

        Returns
        -------
        Margins
            As :meth:`margins`: gain margin (dB), phase margin (degrees), highest gain crossover
            (rad/s); inf/NaN with no crossing.
        """
        import control  # lazy: start-up time (python-control)

        gm, pm, _, _, wp, _ = control.stability_margins(control.frd(self.loop(compensator), self.omega, dt=self.dt),
                                                       returnall=True)
        gm = np.atleast_1d(np.asarray(gm, dtype=float))
        pm = np.atleast_1d(np.asarray(pm, dtype=float))
        gm = gm[np.isfinite(gm) & (gm > 0)]
        pm = pm[np.isfinite(pm)]
        wp = np.atleast_1d(np.asarray(wp, dtype=float))
        return Margins(float(np.min(np.abs(20 * np.log10(gm)))) if gm.size else math.inf,
                       float(np.min(np.abs(pm))) if pm.size else math.inf,
                       float(np.max(wp)) if wp.size and np.isfinite(wp).any() else math.nan)

    def spectral_radius(self, compensator) -> float:
        """The largest pole magnitude of the closed loop (clamp not reached; < 1: stable).

        Parameters
        ----------
        compensator : station.control.Compensator

        Returns
        -------
        float
            max |λ| over the eigenvalues of :meth:`closed_loop_matrix`, dimensionless (< 1: stable).
        """
        return float(np.max(np.abs(np.linalg.eigvals(self.closed_loop_matrix(compensator)))))

    def dominant_mode(self, compensator, band_hz: tuple[float, float] = (0.5, 10.0),
                      poles: np.ndarray | None = None) -> tuple[float, float] | None:
        """The closed loop's least damped oscillatory mode in a band: (f Hz, ζ), or None.

        The slowest-decaying complex pole pair with its damped frequency in ``band_hz`` (the
        step's ringing: the beam's first mode as the loop leaves it); natural frequency and
        damping ratio of its continuous equivalent s = ln(z)/dt.

        Parameters
        ----------
        compensator : station.control.Compensator
        band_hz : tuple of float
            (low, high) of the damped frequency, Hz.
        poles : ndarray, optional
            The closed loop's poles (z), when already known.

        Returns
        -------
        tuple of (float, float) or None
            (natural frequency, Hz; damping ratio ζ, dimensionless) of that mode; None when no
            decaying complex pole has its damped frequency in the band.
        """
        lam = np.linalg.eigvals(self.closed_loop_matrix(compensator)) if poles is None else np.asarray(poles)
        lam = lam[np.abs(lam) > 1e-12].astype(complex)
        s = np.log(lam) / self.dt
        s = s[(s.imag > 2 * math.pi * band_hz[0]) & (s.imag < 2 * math.pi * band_hz[1]) & (s.real < 0)]
        if s.size == 0:
            return None
        p = s[np.argmax(s.real)]
        wn = abs(p)
        return wn / (2 * math.pi), -p.real / wn

    def closed_loop_matrix(self, compensator) -> np.ndarray:
        """The closed loop's state matrix (reference 0).

        States: the plant's, the command's extra delay line (D), the sensors' delay line
        (d samples of θ and a), Ga's and Gth's (controllable canonical form, scipy's tf2ss).

        Parameters
        ----------
        compensator : station.control.Compensator

        Returns
        -------
        ndarray, shape (S, S)
            The state matrix M of x[k+1] = M x[k], S = plant states + extra command delay + 2 d
            + Ga's order + Gth's order.
        """
        A, B, C = self._A, self._B, self._C
        n = A.shape[0]
        D = self.delay - self._d
        d = self._d
        ag, ga_ss = self.accel_gain, _ss(compensator.ga)
        g_ss = _ss(compensator.gth)
        na, ng = ga_ss[0].shape[0], g_ss[0].shape[0]
        size = n + D + 2 * d + na + ng
        i_w, i_q, i_g, i_h = n, n + D, n + D + 2 * d, n + D + 2 * d + na
        # the sensors' readings the controller uses, as rows over the state
        y_th = np.zeros(size)
        y_a = np.zeros(size)
        if d == 0:
            y_th[:n], y_a[:n] = C[0], ag * C[1]
        else:
            y_th[i_q + 2 * (d - 1)] = 1.0
            y_a[i_q + 2 * (d - 1) + 1] = 1.0
        Aa, Ba, Ca, Da = ga_ss
        Ag, Bg, Cg, Dg = g_ss
        ga_out = y_a * Da
        ga_out[i_g:i_g + na] += Ca
        e = -y_th - ga_out
        v = Dg * e
        v[i_h:i_h + ng] += Cg
        M = np.zeros((size, size))
        act = v if D == 0 else np.eye(size)[i_w + D - 1]
        M[:n, :n] = A
        M[:n] += np.outer(B, act)
        if D:
            M[i_w] = v
            for j in range(1, D):
                M[i_w + j, i_w + j - 1] = 1.0
        for j in range(d):
            if j == 0:
                M[i_q, :n], M[i_q + 1, :n] = C[0], ag * C[1]
            else:
                M[i_q + 2 * j, i_q + 2 * (j - 1)] = 1.0
                M[i_q + 2 * j + 1, i_q + 2 * (j - 1) + 1] = 1.0
        if na:
            M[i_g:i_g + na, i_g:i_g + na] = Aa
            M[i_g:i_g + na] += np.outer(Ba, y_a)
        if ng:
            M[i_h:i_h + ng, i_h:i_h + ng] = Ag
            M[i_h:i_h + ng] += np.outer(Bg, e)
        return M


def _ss(tf):
    """(A, B, C, D) of a DiscreteTF (B, C as 1-D, D a float); an absent filter is zero."""
    if tf is None:
        return np.zeros((0, 0)), np.zeros(0), np.zeros(0), 0.0
    return _ss_of(tuple(map(float, tf.num)), tuple(map(float, tf.den)))


@functools.lru_cache(maxsize=256)
def _ss_of(num: tuple, den: tuple):
    # one compensator is checked on every model of a set: its realization once
    num, den = _tf_z(num, den)
    A, B, C, D = scipy.signal.tf2ss(num, den)
    return A, B[:, 0], C[0], float(D[0, 0])


def _grid(lam: np.ndarray, dt: float) -> np.ndarray:
    """Log grid to just below Nyquist, refined around the plant's lightly damped poles."""
    nyq = math.pi / dt
    base = np.logspace(math.log10(0.5), math.log10(nyq * 0.999), GRID_POINTS)
    extra = []
    s = np.log(lam[np.abs(lam) > 0].astype(complex)) / dt
    for p in s:
        w0 = abs(p.imag)
        if 0.5 < w0 < nyq and -p.real < 0.2 * abs(p):
            width = max(-p.real, 1e-3 * w0) * 20
            extra.append(np.linspace(max(0.5, w0 - width), min(nyq * 0.999, w0 + width), 201))
    return np.unique(np.concatenate([base, *extra])) if extra else base


def grid_margins(L: np.ndarray, omega: np.ndarray) -> Margins:
    """Gain and phase margins from a loop's frequency response on a grid.

    Parameters
    ----------
    L : ndarray of complex, shape (W,)
        The loop transfer function (negative feedback).
    omega : ndarray, shape (W,)
        Its frequencies, rad/s, increasing.

    Returns
    -------
    Margins
        Crossings found between grid points by linear interpolation (of log|L| for the gain
        crossovers, of L for the phase crossovers).
    """
    mag = np.abs(L)
    lm = np.log(np.maximum(mag, 1e-300))
    i = np.flatnonzero(lm[:-1] * lm[1:] < 0)
    if i.size:
        f = lm[i] / (lm[i] - lm[i + 1])
        lc = L[i] + f * (L[i + 1] - L[i])
        pm = float(np.min(180.0 - np.degrees(np.abs(np.angle(lc)))))
        wc = float(np.max(omega[i] + f * (omega[i + 1] - omega[i])))
    else:
        pm, wc = math.inf, math.nan
    im = L.imag
    j = np.flatnonzero(im[:-1] * im[1:] < 0)
    gm = math.inf
    if j.size:
        f = im[j] / (im[j] - im[j + 1])
        re = L.real[j] + f * (L.real[j + 1] - L.real[j])
        re = re[re < 0]
        if re.size:
            gm = float(np.min(np.abs(20 * np.log10(np.abs(re)))))
    return Margins(gm, pm, wc)


@functools.lru_cache(maxsize=64)
def loop_model(model, dt: float = DT, alignment: int = ALIGNMENT) -> LoopModel:
    """:class:`LoopModel` of a model, cached (a worker process builds each model's once).

    Parameters
    ----------
    model : station.plant.model.Model
        Hashable (a frozen dataclass).
    dt : float
        Sample time, s.
    alignment : int
        Computational delay d, samples.

    Returns
    -------
    LoopModel
        The model's loop model; the same object for equal arguments (LRU cache, 64 entries).
    """
    return LoopModel(model, dt, alignment)
