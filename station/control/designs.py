"""The rig's compensator designs, compensator files (TOML) and ``make_controller``.

Designs (DESIGN.md "Compensators"; thesis ch. V):

- P: v = kp e.
- Lead: Gth(s) = 5 (p/z) (s + z)/(s + p), p = 2 pi 20 rad/s, z = 2 pi 5 rad/s.
- Accelerometer feedback: Ga(s) = (b1 s + b0)/(s^3 + a2 s^2 + a1 s + a0).

Continuous designs are discretized by Tustin's method at the sample time.

A compensator file is TOML::

    name = "my-lead"          # optional
    limit = 200.0             # optional, the clamp of v: DAC counts in (0, 255]
    [gth]
    num = [20.0, 628.3185307179587]
    den = [1.0, 125.66370614359172]
    domain = "s"              # "s": Tustin at dt; "z": used as given (powers of z^-1)
    [ga]                      # optional, same fields
    [shaper]                  # optional: reference shaper (station.control.shaper)
    times = [0.0, 0.196]      # s, rounded to whole samples
    amplitudes = [0.52, 0.48] # sum 1
    [design]                  # optional: the model it was designed on (station tune writes it)
    model = "rig"             # a built-in model's name, or a model file's path (relative to this file)
    model_sha256 = "..."      # sha256 of that model's canonical TOML (Model.to_toml())

It is read bounded (:func:`station.inputs.load_toml`: a regular UTF-8 file of at most
1 MB) and checked before anything runs: each filter of order at most :data:`MAX_ORDER`,
finite coefficients, a design Tustin can discretize (no pole at s = 2/dt) into finite z
coefficients, and a ``limit`` within :data:`FILE_LIMIT` (the DAC's ±255 at most: a
larger clamp would not be what runs). What the file asks for is what runs, or the file
is refused with one line naming it, the line and the field.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import warnings
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from station.control.compensator import Compensator, OpenLoop
from station.control.contract import DAC_LIMIT
from station.control.shaper import ShaperTimes, check_shaper, make_shaper, shaper_from_spec
from station.control.tf import DiscreteTF, tustin
from station.errors import StationError
from station.inputs import TomlDoc, exists, load_toml
from station.ranges import RangeError, number, shown
from station.rig import CLAMP, DT

_P_LEAD = 2 * math.pi * 20.0
_Z_LEAD = 2 * math.pi * 5.0

LEAD_NUM_S = (5.0 * _P_LEAD / _Z_LEAD, 5.0 * _P_LEAD / _Z_LEAD * _Z_LEAD)
"""Lead Gth(s) numerator, descending powers of s (DESIGN.md)."""
LEAD_DEN_S = (1.0, _P_LEAD)
"""Lead Gth(s) denominator, descending powers of s (DESIGN.md)."""

_A2, _A1, _A0, _B1, _B0 = 36.49022971, 172.1552844, 15.39673089, 467.22634242, 281.56096177
ACCEL_NUM_S = (_B1, _B0)
"""Accelerometer feedback Ga(s) numerator, descending powers of s (DESIGN.md)."""
ACCEL_DEN_S = (1.0, _A2, _A1, _A0)
"""Accelerometer feedback Ga(s) denominator, descending powers of s (DESIGN.md)."""

KINDS = ("p", "lead", "lead-accel", "open-loop")
"""Built-in controller kinds of :func:`make_controller`."""

MAX_ORDER = 20
"""Highest order of a filter read from a compensator file or a log header's spec (the
rig's designs are of order 1 and 3; discretizing and checking a filter costs about the
cube of its order, and an order in the thousands would take hours)."""

MAX_Z_COEFF = 1e9
"""Largest magnitude of a filter's z coefficient (normalized, den_z[0] = 1): the rig's are
below 40; a gain of 1e9 DAC counts per encoder count is no design, and larger ones make
the recursion overflow to inf and NaN."""

FILE_LIMIT = number(0.0, DAC_LIMIT, unit="DAC counts", nonzero=True)
"""The range of a compensator file's ``limit``, ±DAC counts: (0, 255], the DAC's range."""


def _stage(num: Any, den: Any, domain: str, dt: float) -> tuple[DiscreteTF, dict[str, Any]]:
    """One filter and its JSON-able description (continuous design and z coefficients)."""
    if domain == "s":
        num_z, den_z = tustin(num, den, dt)
        desc = {"domain": "s", "num_s": [float(c) for c in num], "den_s": [float(c) for c in den]}
    else:
        tf = DiscreteTF(num, den)
        num_z, den_z = tf.num, tf.den
        desc = {"domain": "z"}
    desc["num_z"] = [float(c) for c in num_z]
    desc["den_z"] = [float(c) for c in den_z]
    return DiscreteTF(num_z, den_z), desc


def _build(kind: str, name: str, gth: tuple, ga: tuple | None, limit: float | None, dt: float,
           extra: dict[str, Any] | None = None, shaper: ShaperTimes | None = None,
           where: str = "[shaper]") -> Compensator:
    gth_tf, gth_desc = _stage(*gth, dt)
    ga_tf, ga_desc = _stage(*ga, dt) if ga is not None else (None, None)
    shaping = None if shaper is None else make_shaper(shaper.times, shaper.amplitudes, dt, where)
    spec: dict[str, Any] = {"kind": kind, "name": name, "dt": dt}
    spec.update(extra or {})
    spec.update({"gth": gth_desc, "ga": ga_desc, "limit": None if limit is None else float(limit)})
    if shaping is not None:  # only then: a log without a shaper keeps the header it always had
        spec["shaper"] = shaping.spec
    return Compensator(gth_tf, ga_tf, limit=limit, name=name, spec=spec, shaper=shaping)


def p_controller(kp: float = 2.0, limit: float | None = CLAMP, dt: float = DT) -> Compensator:
    """Proportional control v = sat(kp e) (thesis: kp = 2).

    Parameters
    ----------
    kp : float
        Gain, DAC counts per encoder count.
    limit : float or None
        Clamp of v, DAC counts.
    dt : float
        Sample time, s (recorded in the spec only).
    """
    return _build("p", "p", ([kp], [1.0], "z"), None, limit, dt, {"kp": float(kp)})


def lead_controller(limit: float | None = CLAMP, dt: float = DT, accel: bool = False) -> Compensator:
    """The rig's lead compensator Gth, optionally with accelerometer feedback Ga (Tustin at dt).

    Parameters
    ----------
    limit : float or None
        Clamp of v, DAC counts.
    dt : float
        Sample time, s.
    accel : bool
        Add the accelerometer feedback Ga ("lead-accel").
    """
    ga = (ACCEL_NUM_S, ACCEL_DEN_S, "s") if accel else None
    kind = "lead-accel" if accel else "lead"
    return _build(kind, kind, (LEAD_NUM_S, LEAD_DEN_S, "s"), ga, limit, dt)


def controller_from_spec(spec: dict[str, Any]) -> Compensator | OpenLoop:
    """Rebuild a controller from the ``spec`` a log header holds (our format).

    Uses the z coefficients as recorded (JSON floats round-trip exactly), the reference
    shaper's delays and amplitudes when the spec has a ``shaper``, and the integer the
    recursion stored when it has a ``recursion`` ("trunc" or "round"; "float-trunc" or
    "float-round": the float remembered, its whole count sent).

    Parameters
    ----------
    spec : dict
        ``Compensator.spec`` or ``OpenLoop.spec`` as written by :mod:`station.runlog`.

    Raises
    ------
    StationError
        If the spec lacks a field or holds bad coefficients.
    """
    try:
        kind = spec["kind"]
        limit = spec.get("limit")
        if kind == "open-loop":
            return OpenLoop(limit=limit)
        stages = []
        for key in ("gth", "ga"):
            desc = spec.get(key)
            if desc is None:
                stages.append(None)
                continue
            tf = DiscreteTF(desc["num_z"], desc["den_z"])
            problem = z_problem(tf.num, tf.den)  # the one check of every filter read
            if problem is not None:
                raise ValueError(f"{key}: {problem}")
            stages.append(tf)
        if stages[0] is None:
            raise KeyError("gth")
        shaper = spec.get("shaper")
        shaping = None if shaper is None else shaper_from_spec(shaper, float(spec.get("dt", DT)))
        return Compensator(stages[0], stages[1], limit=limit, name=str(spec.get("name", kind)), spec=spec,
                           shaper=shaping, recursion=str(spec.get("recursion", "none")))
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise StationError(f"controller spec in log header: bad or missing field {str(exc)[:200]}") from None


def _check_coeffs(doc: TomlDoc, table: str, field: str, value: Any) -> list[float]:
    if not isinstance(value, list) or not value:
        raise doc.error(field, f"expected a non-empty list of numbers, got {shown(value)}", table)
    if len(value) > MAX_ORDER + 1:
        raise doc.error(field, f"{len(value)} coefficients: a filter is of order at most {MAX_ORDER} "
                        f"(at most {MAX_ORDER + 1} coefficients)", table)
    out = []
    for i, c in enumerate(value):
        if isinstance(c, bool) or not isinstance(c, (int, float)) or not math.isfinite(c):
            raise doc.error(field, f"expected a finite number, got {shown(c)}", table, index=i)
        out.append(float(c))
    return out


def _read_stage(doc: TomlDoc, table: str) -> tuple[list[float], list[float], str]:
    stage = doc.data[table]
    if not isinstance(stage, dict):
        raise StationError(f"{doc.path}: [{table}]: expected a table with num, den and domain",
                           file=doc.path, line=doc.line_of(table), key=table)
    unknown = sorted(set(stage) - {"num", "den", "domain"})
    if unknown:
        raise doc.error(unknown[0], "unknown field (expected num, den, domain)", table)
    for key in ("num", "den", "domain"):
        if key not in stage:
            raise doc.error(key, "missing", table)
    domain = stage["domain"]
    if domain not in ("s", "z"):
        raise doc.error("domain", f'expected "s" or "z", got {shown(domain)}', table)
    num = _check_coeffs(doc, table, "num", stage["num"])
    den = _check_coeffs(doc, table, "den", stage["den"])
    if den[0] == 0.0:
        raise doc.error("den", "must not be zero", table, index=0)
    if domain == "s":
        num_t = np.trim_zeros(np.asarray(num), "f")
        if len(num_t) > len(den):
            raise doc.error("num", f"improper design (numerator degree {len(num_t) - 1} > denominator degree "
                            f"{len(den) - 1})", table)
    return num, den, domain


Stage = tuple[list[float], list[float], str]
"""One filter of a compensator file: (num, den, domain), coefficients as written."""


def z_problem(num_z: np.ndarray, den_z: np.ndarray) -> str | None:
    """What is wrong with a filter's z coefficients, None when nothing: the one check of
    every filter read (compensator files, our log headers' specs, the rig's headers).

    Parameters
    ----------
    num_z, den_z : numpy.ndarray, shape (m+1,), (n+1,)
        Normalized coefficients (den_z[0] = 1), ascending powers of z^-1.

    Returns
    -------
    str or None
        "num_z[0] = 1e+12 is outside ±1e+09 (...)", or a coefficient that is not finite;
        None for a filter within :data:`MAX_Z_COEFF` and of order at most :data:`MAX_ORDER`.
    """
    if max(len(num_z), len(den_z)) > MAX_ORDER + 1:
        return f"{max(len(num_z), len(den_z))} coefficients; a filter is of order at most {MAX_ORDER}"
    for name, c in (("num_z", num_z), ("den_z", den_z)):
        if not np.all(np.isfinite(c)):
            return f"{name} holds a number that is not finite"
        big = np.flatnonzero(np.abs(c) > MAX_Z_COEFF)
        if big.size:
            return (f"{name}[{int(big[0])}] = {float(c[big[0]]):.4g} is outside ±{MAX_Z_COEFF:g} (the recursion "
                    f"would overflow)")
    return None


def _check_discretizable(path: Path, table: str, stage: Stage, dt: float) -> None:
    """StationError naming the file and table when an s-domain filter has a pole at s = 2/dt
    (Tustin maps it to z = infinity), or its z coefficients (Tustin at ``dt``, or the
    z-domain ones normalized by den[0]) are not finite or outside ±:data:`MAX_Z_COEFF`."""
    num, den, domain = stage
    with np.errstate(all="ignore"):
        if domain == "s":
            w = 2.0 / dt  # Tustin maps s = 2/dt to z = infinity: den(2/dt) = 0 makes the leading z coefficient 0
            powers = w ** np.arange(len(den) - 1, -1, -1, dtype=float)
            scale = float(np.sum(np.abs(den) * powers))
            if math.isfinite(scale) and abs(float(np.polyval(den, w))) <= 1e-12 * scale:
                raise StationError(f"{path}: [{table}].den: a pole at s = 2/dt = {w:g} rad/s, which Tustin at "
                                   f"dt = {dt:g} s maps to z = infinity (no causal recursion)",
                                   file=path, key=f"[{table}].den")
        try:
            num_z, den_z = tustin(num, den, dt) if domain == "s" else (np.divide(num, den[0]), np.divide(den, den[0]))
            problem = z_problem(np.asarray(num_z, float), np.asarray(den_z, float))
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            problem = str(exc)
    if problem is not None:
        how = f"Tustin at dt = {dt:g} s" if domain == "s" else "normalized by den[0]"
        raise StationError(f"{path}: [{table}]: {how}: {problem}", file=path, key=f"[{table}]")


class DesignRecord(NamedTuple):
    """What a compensator was designed on: a compensator file's ``[design]`` table (DESIGN.md
    "Designing a compensator on a model").

    Attributes
    ----------
    model : str
        The design model: a built-in model's name, or a model file's path as written (relative
        to the compensator file's folder), or a name that is neither (a diagnosis's extended model).
    model_sha256 : str
        64 lowercase hex digits: sha256 of the model's canonical TOML
        (:meth:`station.plant.model.Model.to_toml`, UTF-8), its parameters and effects.
    """

    model: str
    model_sha256: str

    @classmethod
    def of(cls, model: str, model_toml: str) -> DesignRecord:
        """The record of a model: its name or path, and the sha256 of its canonical TOML.

        Parameters
        ----------
        model : str
            How the record names it (a built-in's name, a model file's path).
        model_toml : str
            The model's canonical TOML (:meth:`station.plant.model.Model.to_toml`).
        """
        return cls(str(model), digest(model_toml))

    def matches(self, model_toml: str) -> bool:
        """Whether a model (its canonical TOML) is the one this compensator was designed on.

        Parameters
        ----------
        model_toml : str
            :meth:`station.plant.model.Model.to_toml` of the model at hand.
        """
        return digest(model_toml) == self.model_sha256


def digest(text: str) -> str:
    """sha256 of a text's UTF-8 bytes, 64 lowercase hex digits (a ``[design]`` record's ``model_sha256``).

    Parameters
    ----------
    text : str
    """
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


SHA256_HEX = re.compile(r"[0-9a-f]{64}")
"""A sha256 digest as written in a ``[design]`` record: 64 lowercase hex digits."""


class CompensatorFile(NamedTuple):
    """A compensator file as read and checked, not yet discretized (:func:`read_compensator_file`).

    Attributes
    ----------
    path : Path
        The file.
    name : str
        Its ``name`` (default: the file's stem).
    gth, ga : Stage, Stage or None
        ``(num, den, domain)`` of [gth] and [ga] (None without [ga]).
    limit : float or None
        The clamp the file sets, ±DAC counts in (0, 255] (None: the file sets none).
    sets_limit : bool
        The file has a ``limit``: then it wins over any other (:meth:`clamp`).
    shaper : ShaperTimes or None
        The ``[shaper]``'s times (s, as written; rounded to whole samples when the
        compensator is built) and amplitudes (None without [shaper]).
    design : DesignRecord or None
        The ``[design]`` record: the model it was designed on (None without one).
    """

    path: Path
    name: str
    gth: Stage
    ga: Stage | None
    limit: float | None
    sets_limit: bool
    shaper: ShaperTimes | None = None
    design: DesignRecord | None = None

    def clamp(self, limit: float | None) -> float | None:
        """The clamp the compensator runs with: the file's own ``limit`` wins over ``limit``.

        Parameters
        ----------
        limit : float or None
            The clamp asked for elsewhere (e.g. ``--limit``), ±DAC counts.
        """
        return self.limit if self.sets_limit else limit

    def limit_text(self) -> str:
        """The file's ``limit`` as written in TOML (``150``), for messages ("none" without one)."""
        return "none" if self.limit is None else f"{self.limit:g}"

    def compensator(self, dt: float = DT, limit: float | None = CLAMP) -> Compensator:
        """The compensator, ``domain = "s"`` stages discretized by Tustin at ``dt``.

        Parameters
        ----------
        dt : float
            Sample time, s.
        limit : float or None
            Clamp used when the file has no ``limit``, DAC counts.

        Raises
        ------
        StationError
            A design that cannot be discretized (naming the file and the table), or shaper
            times that fall on the same sample at ``dt``.
        """
        for table, stage in (("gth", self.gth), ("ga", self.ga)):
            if stage is not None:
                _check_discretizable(self.path, table, stage, dt)
        try:
            comp = _build("file", self.name, self.gth, self.ga, self.clamp(limit), dt, {"file": str(self.path)},
                          self.shaper, f"{self.path}: [shaper]")
        except ValueError as exc:
            raise StationError(f"{self.path}: {exc}", file=self.path) from None
        for table, tf in (("gth", comp.gth), ("ga", comp.ga)):
            poles = np.roots(tf.den) if tf is not None and tf.den.size > 1 else np.array([])
            bad = poles[np.abs(poles) > 1.0 + 1e-9]
            if bad.size:
                warnings.warn(f"{self.path}: [{table}]: unstable pole at z = {bad[0]:.4g} (|z| = {abs(bad[0]):.4g} "
                              f"> 1 after discretization at {dt:g} s): the compensator alone diverges",
                              RuntimeWarning, stacklevel=3)
        return comp

    def to_toml(self) -> str:
        """The file's text (TOML): what :func:`read_compensator_file` reads back to the same
        stages, limit, shaper and design record (floats written with ``repr``: they round-trip exactly)."""
        lines = [f"name = {json.dumps(self.name)}"]
        if self.sets_limit:
            lines.append(f"limit = {'false' if self.limit is None else repr(float(self.limit))}")
        for table, stage in (("gth", self.gth), ("ga", self.ga)):
            if stage is not None:
                num, den, domain = stage
                lines += ["", f"[{table}]", f'domain = "{domain}"', f"num = {_floats(num)}", f"den = {_floats(den)}"]
        if self.shaper is not None:
            lines += ["", "[shaper]", f"times = {_floats(self.shaper.times)}  # s",
                      f"amplitudes = {_floats(self.shaper.amplitudes)}"]
        if self.design is not None:
            lines += ["", "[design]", f"model = {json.dumps(self.design.model)}",
                      f"model_sha256 = {json.dumps(self.design.model_sha256)}"]
        return "\n".join(lines) + "\n"


def _floats(values) -> str:
    return "[" + ", ".join(repr(float(x)) for x in values) + "]"


def read_compensator_file(path: str | Path) -> CompensatorFile:
    """Read and check a compensator file (TOML, see the module docstring): the one reading.

    Parameters
    ----------
    path : str or Path
        The TOML file.

    Returns
    -------
    CompensatorFile
        Its stages, name and limit.

    Raises
    ------
    StationError
        Naming the file, the line and the field: not a regular file, larger than 1 MB,
        not UTF-8, invalid or too deeply nested TOML, missing [gth], unknown field, bad
        coefficients, a filter of order above :data:`MAX_ORDER`, bad domain, improper
        design, a limit that is not a number in (0, 255], a [shaper] whose times are not
        increasing from >= 0 s or whose amplitudes do not sum to 1.
    """
    doc = load_toml(path, "compensator file")
    path, data = doc.path, doc.data
    unknown = sorted(set(data) - {"gth", "ga", "limit", "name", "shaper", "design"})
    if unknown:
        raise doc.error(unknown[0], "unknown field (expected gth, ga, limit, name, shaper, design)")
    if "gth" not in data:
        raise StationError(f"{path}: [gth]: missing (the compensator from e to v)", file=path, key="gth")
    gth = _read_stage(doc, "gth")
    ga = _read_stage(doc, "ga") if "ga" in data else None
    limit = None
    if "limit" in data:
        try:
            limit = float(FILE_LIMIT.check(data["limit"]))
        except RangeError as exc:
            raise doc.error("limit", f"the clamp of v: {exc}") from None
    name = data.get("name", path.stem)
    if not isinstance(name, str) or not name:
        raise doc.error("name", f"expected a non-empty string, got {shown(name)}")
    return CompensatorFile(path, name, gth, ga, limit, "limit" in data, _read_shaper(doc), _read_design(doc))


def _read_design(doc) -> DesignRecord | None:
    """The file's [design] record (None without one), checked: a non-empty ``model`` string and
    a ``model_sha256`` of 64 lowercase hex digits, nothing else."""
    if "design" not in doc.data:
        return None
    table = doc.data["design"]
    if not isinstance(table, dict):
        line = doc.line_of("design", None)
        raise StationError(f"{doc.path}:{f' line {line}:' if line else ''} [design]: expected a table with model "
                           f"and model_sha256", file=doc.path, line=line, key="design")
    unknown = sorted(set(table) - {"model", "model_sha256"})
    if unknown:
        raise doc.error(unknown[0], "unknown field (expected model, model_sha256)", table="design")
    # each field in the file's order of reading: what is wrong with the first is said first
    if "model" not in table:
        raise doc.error("model", "missing", table="design")
    model = table["model"]
    if not isinstance(model, str) or not model.strip() or "\n" in model:
        raise doc.error("model", f"expected a model's name or file path (one line), got {shown(model)}", table="design")
    if "model_sha256" not in table:
        raise doc.error("model_sha256", "missing", table="design")
    digest = table["model_sha256"]
    if not isinstance(digest, str) or not SHA256_HEX.fullmatch(digest):
        raise doc.error("model_sha256", f"expected 64 lowercase hex digits (sha256), got {shown(digest)}",
                        table="design")
    return DesignRecord(model, digest)


def _read_shaper(doc) -> ShaperTimes | None:
    """The file's [shaper] (None without one), checked (:func:`station.control.shaper.check_shaper`)."""
    data = doc.data
    if "shaper" not in data:
        return None
    table = data["shaper"]
    line = doc.line_of("shaper", None)
    where = f"{doc.path}: line {line}: [shaper]" if line else f"{doc.path}: [shaper]"
    if not isinstance(table, dict):
        raise StationError(f"{where}: expected a table with times and amplitudes", file=doc.path, line=line,
                           key="shaper")
    unknown = sorted(set(table) - {"times", "amplitudes"})
    if unknown:
        raise doc.error(unknown[0], "unknown field (expected times, amplitudes)", table="shaper")
    for key in ("times", "amplitudes"):
        if key not in table:
            raise doc.error(key, "missing", table="shaper")
    return check_shaper(table["times"], table["amplitudes"], where)


def load_compensator_file(path: str | Path, dt: float = DT, limit: float | None = CLAMP) -> Compensator:
    """Read a compensator file (TOML, see the module docstring) into a compensator.

    Parameters
    ----------
    path : str or Path
        The TOML file.
    dt : float
        Sample time for Tustin discretization of ``domain = "s"`` stages, s.
    limit : float or None
        Clamp used when the file has no ``limit``, DAC counts.

    Returns
    -------
    Compensator
        With ``spec["kind"] == "file"`` and ``spec["file"]`` the path.

    Raises
    ------
    StationError
        As :func:`read_compensator_file`, and a design that cannot be discretized.
    """
    return read_compensator_file(path).compensator(dt, limit)


def make_controller(kind: str, dt: float = DT, kp: float = 2.0,
                    limit: float | None = CLAMP) -> Compensator | OpenLoop:
    """Build a controller by name or from a compensator file.

    Parameters
    ----------
    kind : str
        "p" (v = kp e), "lead" (Gth), "lead-accel" (Gth + Ga), "open-loop" (v = u),
        or a path to a TOML compensator file.
    dt : float
        Sample time, s (0.002 on the rig).
    kp : float
        P gain, DAC counts per encoder count (kind "p" only).
    limit : float or None
        Clamp of v, DAC counts (the rig: 200); None for none. A file's own ``limit``
        takes precedence.

    Returns
    -------
    Compensator or OpenLoop

    Raises
    ------
    StationError
        Unknown kind that is not an existing file, a bad compensator file, or a bad
        kp / limit / dt (not finite, limit not positive).
    """
    if kind in KINDS:
        try:
            if kind == "p":
                return p_controller(kp, limit, dt)
            if kind == "lead":
                return lead_controller(limit, dt)
            if kind == "lead-accel":
                return lead_controller(limit, dt, accel=True)
            return OpenLoop(limit=limit)
        except ValueError as exc:  # a bad kp, limit or dt from the user
            raise StationError(f"controller {kind!r} (kp {kp:g}, limit {limit}, dt {dt:g}): {exc}") from None
    path = Path(kind)
    if not exists(path):
        raise StationError(f"controller {kind!r}: expected one of {', '.join(KINDS)} "
                           f"or a compensator file (TOML); no such file")
    return load_compensator_file(path, dt, limit)
