"""Parameter sets of the SFLR plant: a frozen dataclass read from a TOML file.

The names, values and units are those of DESIGN.md ("FEM plant", parameter table);
everything is SI except the device-side gains (k_tau per DAC count, a_gain in ADC
counts, H in encoder counts).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields
from pathlib import Path

from station.errors import StationError, one_line
from station.inputs import exists, load_toml
from station.ranges import Number, RangeError, number, shown
from station.rig import COUNTS_PER_RAD

PARAMS_DIR = Path(__file__).resolve().parent / "params"
"""Folder of the packaged parameter sets (``<name>.toml``)."""

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
        return COUNTS_PER_RAD

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


PARAM_RANGES: dict[str, Number] = {
    "mu": number(1e-3, 10.0, unit="kg/m"),
    "L": number(0.05, 5.0, unit="m"),
    "EI": number(1e-3, 1e3, unit="N·m²"),
    "drive_k": number(1e-3, 1e3, unit="N·m/rad"),
    "drive_c": number(0.0, 10.0, unit="N·m·s/rad"),
    "clamp_k": number(1e-2, 1e4, unit="N·m/rad"),
    "clamp_c": number(0.0, 10.0, unit="N·m·s/rad"),
    "J_base": number(1e-6, 1.0, unit="kg·m²"),
    "m_accel": number(0.0, 1.0, unit="kg"),
    "J_accel": number(0.0, 1e-2, unit="kg·m²"),
    "act_K": number(1e-4, 10.0),
    "act_p": number(0.1, 1e4, unit="rad/s"),
    "a_gain": number(1e-3, 1e3, unit="counts/(m/s²)"),
    "k_tau": number(1e-5, 1.0, unit="N·m/count"),
    "beam_beta": number(0.0, 1.0, unit="s"),
}
"""The physical range of each field of a parameter set, checked when a set is read
(:func:`params_from_dict`). A bench-top flexible link: about two decades either side of
tmm-fit's values (the diagnosis's param:NAME ratios span one), wide enough for another
rig, narrow enough that every set within them gives a FEM plant that can be computed
(tests/test_input_fuzz.py builds random sets from these ranges)."""

_OPTIONAL = {"beam_beta", "name"}


def _resolve(name_or_path: str | Path) -> Path:
    text = str(name_or_path)
    if text.endswith(".toml") or "/" in text or "\\" in text:
        return Path(text)
    return PARAMS_DIR / f"{text}.toml"


def builtin_params() -> list[str]:
    """Names of the packaged parameter sets (``station/plant/params/*.toml``)."""
    return sorted(p.stem for p in PARAMS_DIR.glob("*.toml"))


def load_params(name_or_path: str | Path = "tmm-fit") -> Params:
    """Read a parameter set from its TOML file (bounded: :func:`station.inputs.load_toml`).

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
        When the file is missing, not a regular file, too large, not UTF-8 or not valid
        TOML, or a field is missing, unknown, not a number, not finite or outside its
        :data:`PARAM_RANGES` range; the message names the file, line and field.
    """
    path = _resolve(name_or_path)
    if path.parent == PARAMS_DIR and not exists(path):
        raise StationError(f"{path}: parameter file not found (packaged sets: {', '.join(builtin_params())})",
                           file=path)
    doc = load_toml(path, "parameter file")
    if not doc.data:  # nothing said: every field its default, silently
        raise StationError(f"{path}: an empty parameter file: expected the parameters it sets", file=path)
    return params_from_dict(doc.data, path, doc.line_of)


def params_from_dict(raw: dict, where: str | Path, line_of: Callable[[str], int | None] | None = None) -> Params:
    """A parameter set from a mapping of the table's names to values (SI units), each field
    checked against its :data:`PARAM_RANGES` range.

    Parameters
    ----------
    raw : dict
        As a parameter-set TOML file holds them (``name`` and ``beam_beta`` optional).
    where : str or Path
        Named in error messages (a file, or a file and its table).
    line_of : callable, optional
        ``line_of(field) -> line number or None`` (e.g. :meth:`station.inputs.TomlDoc.line_of`),
        to name the field's line.

    Returns
    -------
    Params

    Raises
    ------
    StationError
        A field missing, unknown, not a finite number or out of range (naming ``where``,
        the line and the field; ``key`` is the field).
    """
    def bad(name: str, what: str) -> StationError:
        line = line_of(name) if line_of is not None else None
        at = f" line {line}:" if line else ""
        return StationError(one_line(f"{where}:{at} field '{name}': {what}"), line=line, key=name)

    if not isinstance(raw, dict):
        raise StationError(f"{where}: expected a table of the parameter set's fields, got {raw!r}")
    unknown = sorted(set(raw) - {f.name for f in fields(Params)})
    if unknown:
        raise bad(unknown[0], f"unknown field (expected {', '.join(f.name for f in fields(Params))})")
    values: dict[str, object] = {}
    for f in fields(Params):
        if f.name not in raw:
            if f.name in _OPTIONAL:
                continue
            raise StationError(f"{where}: missing field '{f.name}'", key=f.name)
        value = raw[f.name]
        if f.name == "name":
            if not isinstance(value, str):
                raise bad("name", f"expected a string, got {shown(value)}")
            values["name"] = value
            continue
        try:
            values[f.name] = float(PARAM_RANGES[f.name].check(value))
        except RangeError as exc:
            raise bad(f.name, str(exc)) from None
    values.setdefault("name", Path(str(where)).stem)
    return Params(**values)
