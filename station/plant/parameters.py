"""Parameter sets of the SFLR plant: a frozen dataclass read from a TOML file.

The names, values and units are those of DESIGN.md ("FEM plant", parameter table);
everything is SI except the device-side gains (k_tau per DAC count, a_gain in ADC
counts, H in encoder counts).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, fields
from pathlib import Path

from station.errors import StationError

PARAMS_DIR = Path(__file__).resolve().parent / "params"
"""Folder of the packaged parameter sets (``<name>.toml``)."""

COUNTS_PER_REV = 1024
"""Encoder counts per revolution of the base (DESIGN.md, "The rig")."""


@dataclass(frozen=True)
class Params:
    """Physical parameters of the SFLR (DESIGN.md parameter table), SI units.

    Attributes
    ----------
    mu : float
        Beam mass per length, kg/m.
    L : float
        Beam length, m.
    EI : float
        Beam flexural rigidity, N·m².
    drive_k, drive_c : float
        Drive train (motor → base) torsional stiffness N·m/rad and damping N·m·s/rad.
    clamp_k, clamp_c : float
        Clamp (base → beam root) torsional stiffness N·m/rad and damping N·m·s/rad.
    J_base : float
        Base (clamp) inertia, kg·m².
    m_accel, J_accel : float
        Accelerometer point mass (kg) and rotary inertia (kg·m²) at the tip.
    act_K : float
        Actuator gain: motor angle / v = num / (s (s + act_p)) with
        num = act_K·|2πj + act_p| (rad/s² per count).
    act_p : float
        Actuator pole, rad/s.
    a_gain : float
        Accelerometer sensitivity, ADC counts per m/s².
    k_tau : float
        Motor torque per DAC count, N·m/count (0.0106886520727539 for tmm-fit; a fixed
        constant of the set, independent of the element count).
    beam_beta : float
        Stiffness-proportional (Rayleigh) damping coefficient of the beam elements, s
        (C_beam = beam_beta·K_beam). 0 in the fitted set.
    name : str
        Name of the set (informational).
    """

    mu: float
    L: float
    EI: float
    drive_k: float
    drive_c: float
    clamp_k: float
    clamp_c: float
    J_base: float
    m_accel: float
    J_accel: float
    act_K: float
    act_p: float
    a_gain: float
    k_tau: float
    beam_beta: float = 0.0
    name: str = ""

    @property
    def H(self) -> float:
        """Encoder gain, counts/rad (1024/(2π))."""
        return COUNTS_PER_REV / (2.0 * math.pi)

    @property
    def act_num(self) -> float:
        """Actuator numerator act_K·|2πj + act_p|, rad/s² per count (DESIGN.md)."""
        return self.act_K * abs(complex(self.act_p, 2.0 * math.pi))

    @property
    def J_m(self) -> float:
        """Motor inertia J_m = k_tau / act_num, kg·m² (DESIGN.md)."""
        return self.k_tau / self.act_num

    @property
    def c_m(self) -> float:
        """Motor viscous damping c_m = act_p·J_m, N·m·s/rad (DESIGN.md)."""
        return self.act_p * self.J_m


_OPTIONAL = {"beam_beta", "name"}
_NONNEGATIVE = {"drive_c", "clamp_c", "beam_beta", "m_accel", "J_accel"}


def _resolve(name_or_path: str | Path) -> Path:
    text = str(name_or_path)
    if text.endswith(".toml") or "/" in text or "\\" in text:
        return Path(text)
    return PARAMS_DIR / f"{text}.toml"


def load_params(name_or_path: str | Path = "tmm-fit") -> Params:
    """Read a parameter set from its TOML file.

    Parameters
    ----------
    name_or_path : str or Path, default "tmm-fit"
        A packaged set's name (``station/plant/params/<name>.toml``) or a path to a
        TOML file with the DESIGN.md table's names as top-level keys (SI units).

    Returns
    -------
    Params
        The frozen parameter set.

    Raises
    ------
    StationError
        When the file is missing or not valid TOML, or a field is missing, not a
        number, not finite or out of range; the message names the file and field.
    """
    path = _resolve(name_or_path)
    try:
        with open(path, "rb") as fh:
            raw = tomllib.load(fh)
    except FileNotFoundError:
        known = ", ".join(sorted(p.stem for p in PARAMS_DIR.glob("*.toml")))
        raise StationError(f"{path}: parameter file not found (packaged sets: {known})") from None
    except tomllib.TOMLDecodeError as exc:
        raise StationError(f"{path}: not valid TOML: {exc}") from None
    return params_from_dict(raw, path)


def params_from_dict(raw: dict, where: str | Path) -> Params:
    """A parameter set from a mapping of the table's names to values (SI units).

    Parameters
    ----------
    raw : dict
        As a parameter-set TOML file holds them (``name`` and ``beam_beta`` optional).
    where : str or Path
        Named in error messages (a file, or a file and its table).

    Returns
    -------
    Params

    Raises
    ------
    StationError
        A field missing, unknown, not a finite number or out of range (naming ``where``
        and the field).
    """
    path = where
    values: dict[str, object] = {}
    for f in fields(Params):
        if f.name not in raw:
            if f.name in _OPTIONAL:
                continue
            raise StationError(f"{path}: missing field '{f.name}'")
        value = raw[f.name]
        if f.name == "name":
            values["name"] = str(value)
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise StationError(f"{path}: field '{f.name}' must be a finite number, got {value!r}")
        if value < 0 or (value == 0 and f.name not in _NONNEGATIVE):
            raise StationError(f"{path}: field '{f.name}' must be positive, got {value!r}")
        values[f.name] = float(value)
    unknown = sorted(set(raw) - {f.name for f in fields(Params)})
    if unknown:
        raise StationError(f"{path}: unknown field '{unknown[0]}'")
    values.setdefault("name", Path(str(path)).stem)
    return Params(**values)
