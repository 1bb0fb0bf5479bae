"""What `station tune` searches: the rig's compensator structures as a few physical parameters.

The structures are the thesis's (DESIGN.md "Compensators"), written the thesis's way:

- ``p``: v = kp·e.
- ``lead``: Gth(s) = k0·(p/z)·(s + z)/(s + p): k0 the DC gain (DAC counts per encoder
  count; the thesis 5), z the zero (thesis 2π·5 rad/s), p = ratio·z the pole (thesis ratio 4).
- ``lead-accel``: Gth and the accelerometer filter Ga(s) = g·Ga₀(s/σ), the thesis's
  third-order Ga₀ scaled in gain by g and in frequency by σ (its poles and zero times σ,
  its DC gain kept): g = σ = 1 is the thesis's filter.

One step past the thesis's structure, Gth may also hold a filter at the beam's second mode
(about 18 Hz on the rig), multiplying the lead (or P) gain (:data:`FILTERS`):

- ``notch``: N(s) = (s² + 2·d·ζ·ωn·s + ωn²)/(s² + 2·ζ·ωn·s + ωn²), ωn = 2π·notch_hz, ζ the
  notch's width (notch_width) and d its depth (notch_depth, the gain at ωn; 1: no notch);
- ``rolloff``: R(s) = ωr²/(s² + 2·ζr·ωr·s + ωr²), ωr = 2π·rolloff_hz, ζr = rolloff_zeta.

- ``damper`` (lead-accel only): the accelerometer filter Ga also holds a resonant band-pass at
  the second mode, B(s) = k·ωb·(cos φ·s + sin φ·ωb)/(s² + 2·ζb·ωb·s + ωb²), ωb = 2π·damper_hz,
  whose gain k/(2ζb) and phase −φ at ωb are searched (damper_gain, damper_phase in degrees,
  damper_zeta): active damping of the second mode through the accelerometer, outside Gth's
  clamp.

A reference shaper may be added (:mod:`station.control.shaper`): ``zv``/``zvd`` from the
model's first hub-held beam mode (fixed, nothing searched), ``opt``: two impulses at
0 and t2 with amplitudes 1 − A2 and A2, t2 and A2 searched with the rest, or ``opt2``: that
shaper convolved with a second two-impulse shaper (0 and t3, amplitudes 1 − A3 and A3) for
the second mode: four impulses. An ``opt`` search starts each design's shaper at the ZV
shaper of its own closed loop's least damped mode (:meth:`DesignSpace.complete`), ``opt2``'s
second pair at the ZV of its closed loop's least damped mode near the second beam mode: the
impulses then cancel the ringing that loop leaves, and the global bracket only spans the
compensator's own parameters.

The search runs in the unit cube (:meth:`DesignSpace.values`): each parameter maps [0, 1]
to its range, log-spaced for gains and frequencies, so a Sobol sample spreads evenly over
decades and a simplex step means the same everywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.rig import CLAMP, DT
from station.control.designs import (ACCEL_DEN_S, ACCEL_NUM_S, CompensatorFile, DesignRecord, lead_controller,
                                     p_controller)
from station.control.shaper import ShaperTimes, zv_shaper, zvd_shaper

STRUCTURES = ("p", "lead", "lead-accel")
"""The compensator structures `station tune` designs (the rig's own)."""

SHAPERS = ("none", "zv", "zvd", "opt", "opt2")
"""Reference shapers: none, ZV or ZVD of the first beam mode, two impulses searched, or two
pairs searched (the first mode's and the second's, convolved: four impulses)."""

FILTERS = ("none", "notch", "rolloff", "damper")
"""What the compensator may hold beside the structure's own: nothing, a notch or a
second-order roll-off in Gth, or a band-pass in Ga (lead-accel), searched at the beam's second
mode."""

DEFAULT_SHAPER = "opt2"
"""``station tune``'s reference shaper."""

DEFAULT_FILTER = "none"
"""``station tune``'s filter in Gth."""

DEFAULT_TIP_RMS = 1.0
"""``station tune``'s bound on the tip's residual RMS, a multiple of the thesis's compensator's
on the same model: at least as quiet."""

DEFAULT_HUB_RATIO = 0.55
"""``station tune``'s bar on the design model: the hub's settling (2 %) at most this multiple of
the thesis's compensator's there. The hidden rigs' bar is 0.6x; the 0.05 to spare is the spread
of that ratio over rigs near the model (a design at 0.59x on its model met 0.6x on some and not on
others, docs/tuning.md "Where the limit is"), so a rig unlike the model keeps it."""

SECOND_MODE_HZ = (8.0, 40.0)
"""Where a closed loop's second-mode ringing is looked for, Hz (the rig's second beam mode is
at about 18 Hz; a beam 40 % softer or stiffer moves it within this band)."""


@dataclass(frozen=True)
class Parameter:
    """One searched parameter.

    Attributes
    ----------
    name : str
        As in the design's JSON (``kp``, ``k0``, ``z``, ``ratio``, ``ga_gain``, ``ga_freq``,
        ``shaper_t2``, ``shaper_a2``).
    low, high : float
        Its range, in ``unit``.
    log : bool
        Spaced logarithmically in the unit cube.
    unit : str
        Its unit.
    """

    name: str
    low: float
    high: float
    log: bool
    unit: str

    def value(self, x: float) -> float:
        """The parameter at unit-cube coordinate ``x`` (clipped to [0, 1]).

        Parameters
        ----------
        x : float
            Coordinate, 0..1.

        Returns
        -------
        float
            The parameter's value in ``unit``, between ``low`` and ``high`` (geometric
            interpolation when ``log``, linear otherwise).
        """
        x = min(max(float(x), 0.0), 1.0)
        if self.log:
            return math.exp(math.log(self.low) + x * (math.log(self.high) - math.log(self.low)))
        return self.low + x * (self.high - self.low)

    def coordinate(self, value: float) -> float:
        """The unit-cube coordinate of ``value`` (clipped to [0, 1]).

        Parameters
        ----------
        value : float
            In ``unit``.

        Returns
        -------
        float
            The coordinate in [0, 1] (the inverse of :meth:`value` inside the range).
        """
        if self.log:
            x = (math.log(value) - math.log(self.low)) / (math.log(self.high) - math.log(self.low))
        else:
            x = (value - self.low) / (self.high - self.low)
        return min(max(x, 0.0), 1.0)


_TWO_PI = 2 * math.pi
_PARAMETERS = {
    "kp": Parameter("kp", 0.3, 30.0, True, "DAC counts per encoder count"),
    "k0": Parameter("k0", 1.0, 20.0, True, "DAC counts per encoder count"),
    "z": Parameter("z", _TWO_PI * 0.5, _TWO_PI * 20.0, True, "rad/s"),
    "ratio": Parameter("ratio", 1.5, 12.0, True, "1"),
    "ga_gain": Parameter("ga_gain", 0.1, 3.0, True, "1"),
    "ga_freq": Parameter("ga_freq", 0.3, 3.0, True, "1"),
    "shaper_t2": Parameter("shaper_t2", 0.05, 0.8, False, "s"),
    "shaper_a2": Parameter("shaper_a2", 0.0, 0.9, False, "1"),
    "shaper_t3": Parameter("shaper_t3", 0.0125, 0.0625, False, "s"),
    "shaper_a3": Parameter("shaper_a3", 0.0, 0.7, False, "1"),
    "notch_hz": Parameter("notch_hz", 8.0, 40.0, True, "Hz"),
    "notch_depth": Parameter("notch_depth", 0.02, 1.0, True, "1"),
    "notch_width": Parameter("notch_width", 0.05, 1.0, True, "1"),
    "rolloff_hz": Parameter("rolloff_hz", 8.0, 100.0, True, "Hz"),
    "rolloff_zeta": Parameter("rolloff_zeta", 0.3, 1.0, False, "1"),
    "damper_hz": Parameter("damper_hz", 8.0, 40.0, True, "Hz"),
    "damper_gain": Parameter("damper_gain", 0.003, 0.3, True, "encoder counts per accelerometer count"),
    "damper_phase": Parameter("damper_phase", -180.0, 180.0, False, "deg"),
    "damper_zeta": Parameter("damper_zeta", 0.1, 1.0, True, "1"),
}
"""The searched ranges: a decade or more around the thesis's designs (its lead has k0 = 5,
z = 2π·5 rad/s, ratio 4), the accelerometer filter from a tenth to three times the thesis's
in gain and in frequency, a second impulse up to 0.8 s late (half the period of a closed
loop mode down to 0.6 Hz; the first beam mode's is 0.2 s) carrying up to 90 % of the step;
the second mode's pair half a period of 8-40 Hz apart; a notch or roll-off at 8-40 Hz
(8-100 Hz) around the second beam mode, from no notch (depth 1) to 34 dB deep; a damper at
8-40 Hz whose gain at its centre reaches a few tenths of an encoder count per accelerometer
count (the thesis's Ga gives 0.04 at 18 Hz), at any phase."""


THESIS = {"kp": 2.0, "k0": 5.0, "z": _TWO_PI * 5.0, "ratio": 4.0, "ga_gain": 1.0, "ga_freq": 1.0,
          "notch_hz": 18.0, "notch_depth": 1.0, "notch_width": 0.3, "rolloff_hz": 100.0, "rolloff_zeta": 0.7,
          "damper_hz": 18.0, "damper_gain": 0.003, "damper_phase": 0.0, "damper_zeta": 0.3}
"""The thesis's designs in these parameters (DESIGN.md "Compensators"); it has no filter: a
notch of depth 1 (none), a roll-off at 100 Hz (at the range's end, 3° of phase at 5 Hz), a
damper at its least gain."""


def ga_s(gain: float, freq: float) -> tuple[list[float], list[float]]:
    """Ga(s) = gain·Ga₀(s/freq): the thesis's accelerometer filter scaled (descending powers of s).

    Parameters
    ----------
    gain : float
        g, 1 for the thesis's.
    freq : float
        σ: poles and zero times σ, DC gain kept; 1 for the thesis's.

    Returns
    -------
    num, den : list of float
        ``[g·b1·σ², g·b0·σ³]`` and ``[1, a2·σ, a1·σ², a0·σ³]``.
    """
    b1, b0 = ACCEL_NUM_S
    _, a2, a1, a0 = ACCEL_DEN_S
    return [gain * b1 * freq ** 2, gain * b0 * freq ** 3], [1.0, a2 * freq, a1 * freq ** 2, a0 * freq ** 3]


def filter_s(kind: str, values: dict[str, float]) -> tuple[list[float], list[float]] | None:
    """The filter Gth holds beside the structure's gain (module docstring), descending powers of s.

    Parameters
    ----------
    kind : {"none", "notch", "rolloff"}
    values : dict
        ``notch_hz``, ``notch_depth``, ``notch_width`` or ``rolloff_hz``, ``rolloff_zeta``.

    Returns
    -------
    (num, den) or None
        None for "none". Unit DC gain either way.
    """
    if kind == "notch":
        w, zeta, depth = 2 * math.pi * values["notch_hz"], values["notch_width"], values["notch_depth"]
        return [1.0, 2.0 * depth * zeta * w, w * w], [1.0, 2.0 * zeta * w, w * w]
    if kind == "rolloff":
        w, zeta = 2 * math.pi * values["rolloff_hz"], values["rolloff_zeta"]
        return [w * w], [1.0, 2.0 * zeta * w, w * w]
    return None


def damper_s(values: dict[str, float]) -> tuple[list[float], list[float]]:
    """The damper's band-pass B(s) (module docstring), descending powers of s.

    Parameters
    ----------
    values : dict
        ``damper_hz``, ``damper_gain`` (k), ``damper_phase`` (φ, degrees), ``damper_zeta``.

    Returns
    -------
    (num, den)
        At ωb its gain is k/(2ζb) and its phase −φ.
    """
    w = 2 * math.pi * values["damper_hz"]
    k, phi, zeta = values["damper_gain"], math.radians(values["damper_phase"]), values["damper_zeta"]
    return [k * w * math.cos(phi), k * w * w * math.sin(phi)], [1.0, 2.0 * zeta * w, w * w]


def add_s(a, b) -> tuple[list[float], list[float]]:
    """The sum of two transfer functions (num, den), descending powers of s.

    Parameters
    ----------
    a, b : tuple of sequence
        (num, den) each.

    Returns
    -------
    tuple of (list of float, list of float)
        (num, den) of a + b, descending powers of s: num = a_num·b_den + b_num·a_den,
        den = a_den·b_den.
    """
    num = np.polyadd(np.polymul(a[0], b[1]), np.polymul(b[0], a[1]))
    return [float(c) for c in num], [float(c) for c in np.polymul(a[1], b[1])]


def convolve_shapers(a: ShaperTimes, b: ShaperTimes, dt: float = DT) -> ShaperTimes:
    """The shaper whose impulses are every pair's (times added, amplitudes multiplied): ``a``
    then ``b`` (Singer and Seering's convolution of shapers for two modes), the times on the
    sample grid ``dt`` (where the run puts them), impulses on the same sample merged.

    Parameters
    ----------
    a, b : ShaperTimes
        Times (s) and amplitudes, each summing to 1.
    dt : float
        Sample time, s.

    Returns
    -------
    ShaperTimes
        The convolved shaper: times (s, increasing, on the ``dt`` grid) and amplitudes (summing
        to 1).
    """
    pulses = sorted((round((ta + tb) / dt) * dt, aa * ab) for ta, aa in zip(a.times, a.amplitudes)
                    for tb, ab in zip(b.times, b.amplitudes))
    times, amps = [], []
    for t, amp in pulses:
        if times and t - times[-1] < 0.5 * dt:
            amps[-1] += amp
        else:
            times.append(float(t))
            amps.append(float(amp))
    return ShaperTimes(tuple(times), tuple(amps))


def lead_s(k0: float, z: float, ratio: float) -> tuple[list[float], list[float]]:
    """Gth(s) = k0·(p/z)·(s + z)/(s + p), p = ratio·z (descending powers of s).

    Parameters
    ----------
    k0 : float
        DC gain, DAC counts per encoder count.
    z : float
        Zero, rad/s.
    ratio : float
        p/z.

    Returns
    -------
    tuple of (list of float, list of float)
        (num, den) of Gth(s), descending powers of s: ``[k0·ratio, k0·ratio·z]`` and
        ``[1, ratio·z]``; DAC counts per encoder count.
    """
    k = k0 * ratio
    return [k, k * z], [1.0, ratio * z]


@dataclass(frozen=True)
class DesignSpace:
    """A structure, a shaper choice and the clamp: the parameters searched and how they make a compensator.

    Attributes
    ----------
    structure : {"p", "lead", "lead-accel"}
    shaper : {"none", "zv", "zvd", "opt", "opt2"}
    limit : float
        The compensator's clamp, ±DAC counts (written into the file).
    mode : tuple of float or None
        (f Hz, ζ) of the beam mode a ZV/ZVD shaper is made for (None otherwise).
    filter : {"none", "notch", "rolloff"}
        What Gth holds beside the structure's gain (module docstring).
    """

    structure: str
    shaper: str = "none"
    limit: float = CLAMP
    mode: tuple[float, float] | None = None
    filter: str = "none"

    def __post_init__(self) -> None:
        if self.structure not in STRUCTURES:
            raise ValueError(f"structure must be one of {', '.join(STRUCTURES)}, got {self.structure!r}")
        if self.shaper not in SHAPERS:
            raise ValueError(f"shaper must be one of {', '.join(SHAPERS)}, got {self.shaper!r}")
        if self.filter not in FILTERS:
            raise ValueError(f"filter must be one of {', '.join(FILTERS)}, got {self.filter!r}")
        if self.shaper in ("zv", "zvd") and self.mode is None:
            raise ValueError(f"a {self.shaper} shaper needs the mode (f, zeta)")
        if self.filter == "damper" and self.structure != "lead-accel":
            raise ValueError(f"a damper is in the accelerometer filter Ga: lead-accel only, not {self.structure}")

    @property
    def shaper_names(self) -> list[str]:
        """The searched shaper's parameters (the unit cube's last ones)."""
        return {"opt": ["shaper_t2", "shaper_a2"],
                "opt2": ["shaper_t2", "shaper_a2", "shaper_t3", "shaper_a3"]}.get(self.shaper, [])

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """The searched parameters, in the unit cube's order: the structure's, the filter's, the shaper's."""
        names = {"p": ["kp"], "lead": ["k0", "z", "ratio"],
                 "lead-accel": ["k0", "z", "ratio", "ga_gain", "ga_freq"]}[self.structure]
        names += {"notch": ["notch_hz", "notch_depth", "notch_width"],
                  "rolloff": ["rolloff_hz", "rolloff_zeta"],
                  "damper": ["damper_hz", "damper_gain", "damper_phase", "damper_zeta"]}.get(self.filter, [])
        return tuple(_PARAMETERS[n] for n in names + self.shaper_names)

    @property
    def dimension(self) -> int:
        """Number of searched parameters."""
        return len(self.parameters)

    @property
    def controller_dimension(self) -> int:
        """Number of the compensator's own parameters (the first ones; the rest are the shaper's)."""
        return self.dimension - len(self.shaper_names)

    def complete(self, x_controller, mode: tuple[float, float] | None,
                 second: tuple[float, float] | None = None) -> np.ndarray:
        """A whole unit-cube point from the compensator's part and, for ``opt``/``opt2``, the ZV
        shapers of the modes.

        Parameters
        ----------
        x_controller : array_like, shape (controller_dimension,)
            The compensator's coordinates.
        mode : tuple of float or None
            (f Hz, ζ) of the mode the first pair starts at (None: no second impulse).
        second : tuple of float or None
            (f Hz, ζ) of the mode ``opt2``'s second pair starts at (None: none).

        Returns
        -------
        ndarray, shape (dimension,)
            The point: ``x_controller`` followed by each shaper pair's (time, amplitude)
            coordinates; ``x_controller`` itself for the other shapers.

        Raises
        ------
        ValueError
            A ``mode`` or ``second`` whose frequency is not positive or whose damping ratio is
            outside [0, 1) (:func:`~station.control.shaper.zv_shaper`).
        """
        x = np.asarray(x_controller, dtype=float)
        if self.shaper not in ("opt", "opt2"):
            return x
        parts = [x]
        for (t, a), m in zip(zip(self.shaper_names[0::2], self.shaper_names[1::2]), (mode, second)):
            pt, pa = _PARAMETERS[t], _PARAMETERS[a]
            if m is None:
                parts.append([pt.coordinate(0.5 * (pt.low + pt.high)), 0.0])
            else:
                zv = zv_shaper(*m)
                parts.append([pt.coordinate(zv.times[1]), pa.coordinate(zv.amplitudes[1])])
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def values(self, x) -> dict[str, float]:
        """The parameters at unit-cube point ``x``.

        Parameters
        ----------
        x : array_like, shape (dimension,)
            Coordinates, each clipped to [0, 1].

        Returns
        -------
        dict of str to float
            Each parameter's name to its value in its ``unit``.
        """
        return {p.name: p.value(xi) for p, xi in zip(self.parameters, np.asarray(x, dtype=float))}

    def thesis_point(self) -> np.ndarray:
        """The unit-cube coordinates of the thesis's compensator (its own parameters only).

        Returns
        -------
        ndarray, shape (controller_dimension,)
            Coordinates in [0, 1] of the thesis's parameters (clipped to the ranges).
        """
        return np.array([p.coordinate(THESIS[p.name]) for p in self.parameters[:self.controller_dimension]])

    def shaper_times(self, values: dict[str, float]) -> ShaperTimes | None:
        """The shaper of a design (None for "none").

        Parameters
        ----------
        values : dict
            The design's parameters (``shaper_t2``, ``shaper_a2`` for "opt").

        Returns
        -------
        ShaperTimes or None
            Impulse times (s) and amplitudes (summing to 1): ZV or ZVD at :attr:`mode`, or the
            searched pair (``opt``) or the convolution of the two searched pairs (``opt2``); None for
            "none".

        Raises
        ------
        ValueError
            ``zv``/``zvd`` with a :attr:`mode` whose frequency is not positive or whose damping
            ratio is outside [0, 1) (:func:`~station.control.shaper.zv_shaper`).
        """
        if self.shaper == "none":
            return None
        if self.shaper == "zv":
            return zv_shaper(*self.mode)
        if self.shaper == "zvd":
            return zvd_shaper(*self.mode)
        a2 = values["shaper_a2"]
        first = ShaperTimes((0.0, values["shaper_t2"]), (1.0 - a2, a2))
        if self.shaper == "opt":
            return first
        a3 = values["shaper_a3"]
        return convolve_shapers(first, ShaperTimes((0.0, values["shaper_t3"]), (1.0 - a3, a3)))

    def compensator_file(self, values: dict[str, float], name: str = "tuned",
                         path: str | Path = "tuned.toml", design: DesignRecord | None = None) -> CompensatorFile:
        """The design as a compensator file (continuous stages, Tustin at the run's dt).

        Parameters
        ----------
        values : dict
            The design's parameters (:meth:`values`).
        name : str
            The file's ``name``.
        path : str or Path
            Where it is (or will be) written.
        design : DesignRecord, optional
            The model it was designed on (the file's ``[design]`` record).

        Returns
        -------
        station.control.files.CompensatorFile
            The file's contents (not written): Gth and, for lead-accel, Ga as continuous
            (num, den) in s (P: a constant in z), the clamp, the shaper and the design record.
        """
        if self.structure == "p":
            num, den = [values["kp"]], [1.0]
        else:
            num, den = lead_s(values["k0"], values["z"], values["ratio"])
        extra = filter_s(self.filter, values) if self.filter in ("notch", "rolloff") else None
        if extra is None:
            gth = (num, den, "z" if self.structure == "p" else "s")
        else:
            gth = ([float(c) for c in np.polymul(num, extra[0])], [float(c) for c in np.polymul(den, extra[1])], "s")
        ga = None
        if self.structure == "lead-accel":
            num, den = ga_s(values["ga_gain"], values["ga_freq"])
            if self.filter == "damper":
                num, den = add_s((num, den), damper_s(values))
            ga = (num, den, "s")
        return CompensatorFile(Path(path), name, gth, ga, float(self.limit), True, self.shaper_times(values), design)


def thesis_compensator(structure: str, limit: float = CLAMP, dt: float = DT):
    """The thesis's compensator of a structure (``station step --controller KIND``).

    Parameters
    ----------
    structure : {"p", "lead", "lead-accel"}
    limit : float
        Clamp, ±DAC counts.
    dt : float
        Sample time, s.

    Returns
    -------
    station.control.Compensator
        P with kp = 2, or the thesis's lead (with accelerometer feedback for "lead-accel"),
        clamped at ±``limit`` DAC counts.
    """
    if structure == "p":
        return p_controller(THESIS["kp"], limit, dt)
    return lead_controller(limit, dt, accel=structure == "lead-accel")
