"""What `station tune` searches: the rig's compensator structures as a few physical parameters.

The structures are the thesis's (DESIGN.md "Compensators"), written the thesis's way:

- ``p``: v = kp·e.
- ``lead``: Gth(s) = k0·(p/z)·(s + z)/(s + p): k0 the DC gain (DAC counts per encoder
  count; the thesis 5), z the zero (thesis 2π·5 rad/s), p = ratio·z the pole (thesis ratio 4).
- ``lead-accel``: Gth and the accelerometer filter Ga(s) = g·Ga₀(s/σ), the thesis's
  third-order Ga₀ scaled in gain by g and in frequency by σ (its poles and zero times σ,
  its DC gain kept): g = σ = 1 is the thesis's filter.

A reference shaper may be added (:mod:`station.control.shaper`): ``zv``/``zvd`` from the
model's first hub-held beam mode (fixed, nothing searched), or ``opt``: two impulses at
0 and t2 with amplitudes 1 − A2 and A2, t2 and A2 searched with the rest. An ``opt`` search
starts each design's shaper at the ZV shaper of its own closed loop's least damped mode
(:meth:`DesignSpace.complete`): the impulses then cancel the ringing that loop leaves, and
the global bracket only spans the compensator's own parameters.

The search runs in the unit cube (:meth:`DesignSpace.values`): each parameter maps [0, 1]
to its range, log-spaced for gains and frequencies, so a Sobol sample spreads evenly over
decades and a simplex step means the same everywhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.control.designs import ACCEL_DEN_S, ACCEL_NUM_S, CompensatorFile, lead_controller, p_controller
from station.control.shaper import ShaperTimes, zv_shaper, zvd_shaper

STRUCTURES = ("p", "lead", "lead-accel")
"""The compensator structures `station tune` designs (the rig's own)."""

SHAPERS = ("none", "zv", "zvd", "opt")
"""Reference shapers: none, ZV or ZVD of the first beam mode, or two impulses searched."""


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
}
"""The searched ranges: a decade or more around the thesis's designs (its lead has k0 = 5,
z = 2π·5 rad/s, ratio 4), the accelerometer filter from a tenth to three times the thesis's
in gain and in frequency, a second impulse up to 0.8 s late (half the period of a closed
loop mode down to 0.6 Hz; the first beam mode's is 0.2 s) carrying up to 90 % of the step."""


THESIS = {"kp": 2.0, "k0": 5.0, "z": _TWO_PI * 5.0, "ratio": 4.0, "ga_gain": 1.0, "ga_freq": 1.0}
"""The thesis's designs in these parameters (DESIGN.md "Compensators")."""


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
    """
    k = k0 * ratio
    return [k, k * z], [1.0, ratio * z]


@dataclass(frozen=True)
class DesignSpace:
    """A structure, a shaper choice and the clamp: the parameters searched and how they make a compensator.

    Attributes
    ----------
    structure : {"p", "lead", "lead-accel"}
    shaper : {"none", "zv", "zvd", "opt"}
    limit : float
        The compensator's clamp, ±DAC counts (written into the file).
    mode : tuple of float or None
        (f Hz, ζ) of the beam mode a ZV/ZVD shaper is made for (None otherwise).
    """

    structure: str
    shaper: str = "none"
    limit: float = 200.0
    mode: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if self.structure not in STRUCTURES:
            raise ValueError(f"structure must be one of {', '.join(STRUCTURES)}, got {self.structure!r}")
        if self.shaper not in SHAPERS:
            raise ValueError(f"shaper must be one of {', '.join(SHAPERS)}, got {self.shaper!r}")
        if self.shaper in ("zv", "zvd") and self.mode is None:
            raise ValueError(f"a {self.shaper} shaper needs the mode (f, zeta)")

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """The searched parameters, in the unit cube's order."""
        names = {"p": ["kp"], "lead": ["k0", "z", "ratio"],
                 "lead-accel": ["k0", "z", "ratio", "ga_gain", "ga_freq"]}[self.structure]
        if self.shaper == "opt":
            names += ["shaper_t2", "shaper_a2"]
        return tuple(_PARAMETERS[n] for n in names)

    @property
    def dimension(self) -> int:
        """Number of searched parameters."""
        return len(self.parameters)

    @property
    def controller_dimension(self) -> int:
        """Number of the compensator's own parameters (the first ones; the rest are the shaper's)."""
        return self.dimension - (2 if self.shaper == "opt" else 0)

    def complete(self, x_controller, mode: tuple[float, float] | None) -> np.ndarray:
        """A whole unit-cube point from the compensator's part and, for ``opt``, the ZV shaper of a mode.

        Parameters
        ----------
        x_controller : array_like, shape (controller_dimension,)
            The compensator's coordinates.
        mode : tuple of float or None
            (f Hz, ζ) of the mode the shaper starts at (None: no second impulse).
        """
        x = np.asarray(x_controller, dtype=float)
        if self.shaper != "opt":
            return x
        t2, a2 = self.parameters[-2:]
        if mode is None:
            return np.r_[x, t2.coordinate(0.5 * (t2.low + t2.high)), 0.0]
        zv = zv_shaper(*mode)
        return np.r_[x, t2.coordinate(zv.times[1]), a2.coordinate(zv.amplitudes[1])]

    def values(self, x) -> dict[str, float]:
        """The parameters at unit-cube point ``x``.

        Parameters
        ----------
        x : array_like, shape (dimension,)
            Coordinates, each clipped to [0, 1].
        """
        return {p.name: p.value(xi) for p, xi in zip(self.parameters, np.asarray(x, dtype=float))}

    def thesis_point(self) -> np.ndarray:
        """The unit-cube coordinates of the thesis's compensator (its own parameters only)."""
        return np.array([p.coordinate(THESIS[p.name]) for p in self.parameters[:self.controller_dimension]])

    def shaper_times(self, values: dict[str, float]) -> ShaperTimes | None:
        """The shaper of a design (None for "none").

        Parameters
        ----------
        values : dict
            The design's parameters (``shaper_t2``, ``shaper_a2`` for "opt").
        """
        if self.shaper == "none":
            return None
        if self.shaper == "zv":
            return zv_shaper(*self.mode)
        if self.shaper == "zvd":
            return zvd_shaper(*self.mode)
        a2 = values["shaper_a2"]
        return ShaperTimes((0.0, values["shaper_t2"]), (1.0 - a2, a2))

    def compensator_file(self, values: dict[str, float], name: str = "tuned",
                         path: str | Path = "tuned.toml") -> CompensatorFile:
        """The design as a compensator file (continuous stages, Tustin at the run's dt).

        Parameters
        ----------
        values : dict
            The design's parameters (:meth:`values`).
        name : str
            The file's ``name``.
        path : str or Path
            Where it is (or will be) written.
        """
        if self.structure == "p":
            gth = ([values["kp"]], [1.0], "z")
        else:
            gth = (*lead_s(values["k0"], values["z"], values["ratio"]), "s")
        ga = (*ga_s(values["ga_gain"], values["ga_freq"]), "s") if self.structure == "lead-accel" else None
        return CompensatorFile(Path(path), name, gth, ga, float(self.limit), True, self.shaper_times(values))


def thesis_compensator(structure: str, limit: float = 200.0, dt: float = 0.002):
    """The thesis's compensator of a structure (``station step --controller KIND``).

    Parameters
    ----------
    structure : {"p", "lead", "lead-accel"}
    limit : float
        Clamp, ±DAC counts.
    dt : float
        Sample time, s.
    """
    if structure == "p":
        return p_controller(THESIS["kp"], limit, dt)
    return lead_controller(limit, dt, accel=structure == "lead-accel")
