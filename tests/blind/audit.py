"""Logs for the log audit: headers that lie, and commands from a lab's integer recursions.

From DESIGN.md ("Log audit", "Compensators", "Timing and log rows") and issue 26 alone,
importing nothing from the station. Each case is one rig-format run of 2000 samples (4 s,
like the lab's third session) on the blind rig (:mod:`tests.blind.rig`: its FEM, amplifier,
friction and sensors), with a controller the lab could have run:

- a P law v = Q(sat(kp·e)) or a lead Gth(s) = K(s+z)/(s+p) discretized by Tustin (the
  generator's own, scipy's ``bilinear``), its recursion on the float command or on the
  integer the lab's software stored, v[k] = sat(Q(Σ b_i e[k-i] − Σ a_j v[k-j])) with Q
  truncation toward zero or rounding (halves away from zero);
- at alignment 0 (v[k] from θ[k], the 2009 software) or 1 (from θ[k-1]);
- the rig's clamp ±200, or ±150 on some seeds;
- a step (at tick 10), a 5 Hz sine or the lab's "0-10 Hz" sweep reference (to 20 Hz).

Classes (:data:`CLASSES`): headers that lie ("lie:open_loop": an open-loop header on
closed-loop data; "lie:p_kp": a P header with the wrong kp; "lie:lead_pole": the thesis's
lead printed in the header, another pole in the data); integer recursions with no header
(the 2014 layout, "int:trunc_d0" ... "int:round_d1"); "lie:accel_fb": a lead with
accelerometer feedback θ̂_d = u − Ga(a) (DESIGN.md's Ga(s), its gain and frequency scaled),
under a header that leaves Ga out (open loop, or the lead alone), its recursion on the float
command (as the thesis's software ran it), at either alignment; the lab's third session ("session":
an open-loop header on a lead run on the truncated integer at alignment 0); "lie:sent": an
open-loop header on a lead whose recursion runs on the float while the whole count it sends
is logged, at either alignment; "lie:accel_int": an open-loop header on a lead with DESIGN.md's
accelerometer feedback Ga as it stands, the command stored or sent as a whole count (any of
the four ways); truthful headers
the audit must confirm ("honest:p", "honest:lead_int"; "honest:lead_sent": a lead whose
recursion runs on the float while the whole count it sends is logged, "float-trunc" or
"float-round"); "words": a true header (a P or a lead on the stored integer) over a log whose
signed columns (u, v, θ, a, θ̂_d where whole) the lab's client read from the legacy protocol's
16-bit two's-complement words as unsigned, a negative x written as 65536 + x; "swap": a true
header (a P, or a lead on the stored integer), or none (the 2014 layout), over a log whose columns u and v, or θ and a,
hold each other's values (a script that wrote them in another order than it named them);
"rows": a true header (a P, or a lead on the stored integer), or none (the 2014 layout,
t jumping), over a log that lost rows (one to
three spans of 1-30 ticks while the hub moves, n and t jumping over them) or holds a span of
rows written again (a logger that re-sent a block); "a_unit": a true header (a P, or a lead on the
stored integer) or none over a log whose a column a script scaled into m/s², g or mV (a count
1/1.145 m/s², 1/11.23 g or 3300/4096 mV) and printed to 7 digits; "v_unit": a true header (a P,
or a lead on the stored integer or the float) over a log whose v a script wrote in volts of a ±5 V 12-bit or a
±10 V 16-bit converter (a count 5/2048 or 10/32768 V), 7 digits; "printed": a lead on the float
command under its true header or an open-loop one, every number printed to 5 significant digits
(MATLAB's csvwrite) or 6 (C's %g); "sign": θ written with the other sign than the loop fed back,
under a true header, none or an open-loop one; "double": the lab's session (an open-loop header
on a lead on the truncated integer) with one column fault beside it (v in volts, θ negated, u
and v swapped, or, on the float, every number printed to 5 or 6 digits); "lie:swap": a closed-loop
header that lies (a P header's kp over another gain, or the thesis's lead printed over another
pole) with u and v, or θ and a, written in each other's place; "pair": two column faults at once under
a true header (a P, or a lead on the stored integer) or none: two columns swapped and θ negated, or
(under a true header) two columns swapped and v written in volts; "v_zero": a true header (a P, or a
lead on the stored integer), none, or the lab's session's open-loop one over a log whose v a
script wrote as an unsigned DAC code about its midpoint (128, 2048 or 32768: 8, 12 or 16 bits); "u_unit":
the same headers over a log whose u (the reference) a script wrote in degrees or radians of the
hub, θ left in encoder counts; "theta_zero": the same headers over a log whose θ a script wrote
as the encoder read it, from a count θ0 left by an earlier run, where its loop took θ0 off (the
lab's client reads θ0 at START: the error u − (θ − θ0)); "a_zero": the thesis's lead + accelerometer
feedback under its true header, on the float command or the whole count stored or sent, over a
log whose a a script wrote as the accelerometer read it where the loop fed Ga the reading less a
calibrated zero a0 (the rig's logs read a about 0.04 at rest); "lie:a_zero": the same under an
open-loop header or none, a lead and a scaled Ga of their own on the float command; "lie:column": a
closed-loop header that lies (as "lie:swap"'s) over one column fault ("v_unit", on a lead's stored
integer; "v_zero"; "theta_zero"; "u_unit"); "lie:accel_rows": "lie:accel_fb"'s law and headers, or
none, over a log that lost rows (one to three spans of 1-30 ticks, the first from tick 150 on:
Ga's state is in no column, so only the rows before the first jump can show its law, and a
law of up to 14 coefficients needs more than a few); "rows:column": a true header (a P, a lead on
the stored integer, or the thesis's lead + Ga on the float command, both named) over a log that
lost rows (as "rows") and holds one column fault beside it (θ negated, u and v or θ and a
swapped, or v in volts); "zero:column": "theta_zero"'s headers and θ from an earlier run's count,
beside θ negated or u and v swapped (the script that kept the encoder's count also wrote the
angle with the other sign, or its columns in another order); "zero:command": the same headers and
θ0, beside v in volts ("v_unit"'s; a P's only under its own header) or about a DAC code's midpoint
("v_zero"'s): a script that wrote the device's raw words; "three:columns": "zero:command"'s two
faults under a true header (a P, or a lead on the stored integer), beside θ negated or u and v
swapped: three column faults at once; "four:columns": the same with θ negated and u and v swapped
both (four at once); "three:open_loop": "three:columns"'s three under the lab's session's
open-loop header or none (the law inferred; v about a DAC code's midpoint, or a lead's stored
integer in volts). A class joined with "+" to
"coulomb_friction" hides that friction too (drawn as :func:`tests.blind.cases.draw` draws it).
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tests.blind.cases import draw
from tests.blind.generator import COLUMNS, COLUMNS_ACCEL, _coeffs, _num
from tests.blind.rig import DT, Amplifier, Effects, Run, encoder, gth_design, make_plant, tustin

N = 2000
"""Samples per run (4 s at 500 Hz)."""

CLASSES = ("lie:open_loop", "lie:p_kp", "lie:lead_pole", "lie:accel_fb", "int:trunc_d0", "int:trunc_d1",
           "int:round_d0", "int:round_d1", "session", "lie:sent", "lie:accel_int", "honest:p", "honest:lead_int",
           "honest:lead_sent", "words", "swap", "rows", "a_unit", "v_unit", "printed", "sign", "double", "lie:swap", "pair",
           "v_zero", "u_unit", "theta_zero", "a_zero", "lie:a_zero", "lie:column", "lie:accel_rows", "rows:column",
           "zero:column", "zero:command", "three:columns", "four:columns", "three:open_loop")
"""The audit's blind classes, in the validation table's order."""

PHYSICAL = ("coulomb_friction",)
"""Physical effects a class may be joined with ("lie:p_kp+coulomb_friction")."""

LEAD_GAINS = (1.0, 1.5, 2.0, 2.5, 3.0, 4.0)
P_GAINS = (0.5, 0.8, 1.0, 1.2, 1.5, 2.5, 3.0)
OTHER_POLES_HZ = (8.0, 10.0, 12.0, 15.0, 25.0, 30.0, 40.0)
"""The lead-pole lie's pole frequencies, Hz (the thesis's is 20)."""

HEADER_KP = 2.0
"""The gain a lying P header states."""

GA_S = ((467.22634242, 281.56096177), (1.0, 36.49022971, 172.1552844, 15.39673089))
"""DESIGN.md's accelerometer feedback Ga(s) = (b1 s + b0)/(s³ + a2 s² + a1 s + a0)."""

A_UNITS = {"m/s²": 1.0 / 1.1452654922936827, "g": 1.0 / (1.1452654922936827 * 9.80665), "mV": 3300.0 / 4096}
"""One accelerometer count in the units the "a_unit" class writes a in (DESIGN.md's a_gain, counts
per m/s²; a 3.3 V 12-bit converter's mV)."""

V_UNITS = {"V of ±5 V, 12 bits": 5.0 / 2048, "V of ±10 V, 16 bits": 10.0 / 32768}
"""One DAC count in the volts the "v_unit" class writes v in."""

V_ZEROS = (128.0, 2048.0, 32768.0)
"""The zeros the "v_zero" class writes v about: an unsigned 8-, 12- or 16-bit DAC code's midpoint."""

U_UNITS = {"degrees": 360.0 / 1024, "radians": 2.0 * math.pi / 1024}
"""One encoder count (1024/rev) in the units the "u_unit" class writes u in."""

GA_GAINS = (0.5, 0.75, 1.0, 1.5)
GA_FREQUENCIES = (0.7, 1.0, 1.4)
"""Scales of Ga's gain and of its frequencies (Ga(s/f)) the accel_fb class draws."""


@dataclass(frozen=True)
class AuditCase:
    """What one audit case hides and what its header says.

    Attributes
    ----------
    name : str
        Its class (and "+coulomb_friction").
    law : {"p", "lead"}
    kp : float or None
        The P gain.
    num_s, den_s : tuple of float or None
        The lead's continuous design (descending powers of s), Tustin at 0.002 s.
    design_text : str
        The design as a person writes it, e.g. "3(s+13)/(s+20)".
    recursion : {"none", "trunc", "round", "float-trunc", "float-round"}
    alignment : int
    limit : float
        The clamp, DAC counts.
    header : {"open-loop", "p", "lead", "none"}
        What the header names ("none": the 2014 layout, no header).
    header_kp : float or None
    reference : {"step", "sine", "sweep"}
    amplitude : float
    effects : dict
        Hidden physical effects.
    ga_s : (tuple, tuple) or None
        The accelerometer feedback's continuous design (num, den, descending powers of s).
    words : bool
        Whether the signed columns are written as unsigned 16-bit words.
    wrapped : tuple of str
        The columns that held a negative value, so written as 65536 + x ("u", "v", "theta",
        "a", "theta_d_hat"): filled in by :func:`write_audit_case`.
    swap : tuple of str
        Two columns written in each other's place (("u", "v") or ("theta", "a")), else ().
    rows : tuple of int
        The ticks the log's rows hold, in the order written ((): every tick once, in order).
    a_unit : str or None
        The unit a is written in (:data:`A_UNITS`), else None (counts).
    v_unit : str or None
        The unit v is written in (:data:`V_UNITS`), else None (counts).
    digits : int or None
        The significant digits every number is printed to ("printed"), else None (in full).
    negate : bool
        Whether θ is written with the other sign than the loop fed back ("sign"); after
        :func:`write_case`, only where that changed θ (a hub held at 0 all run is θ either sign).
    v_zero : float or None
        The zero v is written about (:data:`V_ZEROS`, "v_zero"), else None (about 0).
    u_unit : str or None
        The unit u is written in (:data:`U_UNITS`, "u_unit"), else None (encoder counts).
    theta_zero : float or None
        The encoder's count at the start, written in θ but taken off by the loop ("theta_zero"),
        else None.
    a_zero : float or None
        The accelerometer's zero, written in a but taken off by the loop's Ga ("a_zero"), else None.
    ga_recursion : {"none", "trunc", "round"}
        What Ga's recursion remembers of its output: the float, or the whole count the lab's 2009
        software stored in an int32 array (its θ̂_d = u − that count); not "none": the header names Ga.
    """

    name: str
    law: str
    kp: float | None
    num_s: tuple | None
    den_s: tuple | None
    design_text: str
    recursion: str
    alignment: int
    limit: float
    header: str
    header_kp: float | None
    reference: str
    amplitude: float
    effects: dict = field(default_factory=dict)
    ga_s: tuple | None = None
    words: bool = False
    wrapped: tuple = ()
    swap: tuple = ()
    rows: tuple = ()
    a_unit: str | None = None
    v_unit: str | None = None
    digits: int | None = None
    negate: bool = False
    v_zero: float | None = None
    u_unit: str | None = None
    theta_zero: float | None = None
    a_zero: float | None = None
    ga_recursion: str = "none"

    @property
    def lies(self) -> bool:
        """Whether the header names another controller than the data's."""
        if self.name.startswith(("printed", "sign", "double", "v_zero", "u_unit", "theta_zero", "a_zero",
                                 "lie:a_zero", "zero:column", "zero:command", "three:columns", "four:columns",
                                 "three:open_loop")):
            return self.header == "open-loop"
        if self.name.startswith("lie:accel_rows"):
            return self.header != "none"
        return self.name.split("+")[0] in ("lie:open_loop", "lie:p_kp", "lie:lead_pole", "lie:accel_fb", "session", "lie:sent",
                                              "lie:accel_int", "lie:swap", "lie:column")


def _rng(name: str, seed: int) -> np.random.Generator:
    return np.random.default_rng([zlib.crc32(("audit/" + name).encode()), seed])


def _lead_text(k: float, z: float, p: float, hz: bool = False) -> str:
    if hz:
        return f"{k:g}(s+2π·{z / (2 * math.pi):g})/(s+2π·{p / (2 * math.pi):g})"
    return f"{k:g}(s+{z:g})/(s+{p:g})"


def draw_case(name: str, seed: int) -> AuditCase:
    """The hidden controller, header and reference of a class for a seed (deterministic).

    Parameters
    ----------
    name : str
        A class of :data:`CLASSES`, optionally "+coulomb_friction".
    seed : int

    Raises
    ------
    ValueError
        An unknown class or physical effect.
    """
    base, *extra = name.split("+")
    if base not in CLASSES or any(e not in PHYSICAL for e in extra):
        raise ValueError(f"unknown audit case {name!r}; classes: {', '.join(CLASSES)}, joined with "
                         f"{', '.join(PHYSICAL)}")
    rng = _rng(base, seed)
    effects = {e: draw(e, seed) for e in extra}
    reference = str(rng.choice(["step", "step", "sine", "sweep"]))
    amplitude = float(rng.integers(30, 151)) if reference == "step" else float(rng.integers(20, 61))
    limit = 150.0 if rng.random() < 0.3 else 200.0
    k, z = float(rng.choice(LEAD_GAINS)), float(rng.integers(5, 31))
    p = z + float(rng.integers(5, 61))
    kp = float(rng.choice(P_GAINS))
    lead = dict(law="lead", kp=None, num_s=(k, k * z), den_s=(1.0, p), design_text=_lead_text(k, z, p))
    p_law = dict(law="p", kp=kp, num_s=None, den_s=None, design_text=f"P, kp = {kp:g}")
    common = dict(name=name, limit=limit, reference=reference, amplitude=amplitude, effects=effects,
                  header_kp=None)
    if base == "lie:open_loop":
        return AuditCase(**common, **lead, recursion="none", alignment=1, header="open-loop")
    if base == "lie:p_kp":
        kp = float(rng.choice([g for g in P_GAINS if g != HEADER_KP]))
        p_law.update(kp=kp, design_text=f"P, kp = {kp:g}")
        return AuditCase(**{**common, "header_kp": HEADER_KP}, **p_law, recursion="none", alignment=1, header="p")
    if base == "lie:lead_pole":
        zz, pp = 2 * math.pi * 5, 2 * math.pi * float(rng.choice(OTHER_POLES_HZ))
        kk = 5.0 * pp / zz
        return AuditCase(**common, law="lead", kp=None, num_s=(kk, kk * zz), den_s=(1.0, pp),
                         design_text=_lead_text(kk, zz, pp, hz=True), recursion="none", alignment=1, header="lead")
    if base in ("lie:accel_fb", "lie:accel_rows"):
        g, f = float(rng.choice(GA_GAINS)), float(rng.choice(GA_FREQUENCIES))
        (b1, b0), (_, a2, a1, a0) = GA_S
        ga = ((g * b1 * f, g * b0 * f * f), (1.0, a2 * f, a1 * f * f, a0 * f ** 3))  # g·Ga(s/f)
        if base == "lie:accel_fb":
            return AuditCase(**common, **lead, recursion="none", alignment=int(rng.integers(0, 2)),
                             header=str(rng.choice(["open-loop", "lead"])), ga_s=ga)
        lost = np.zeros(N, dtype=bool)
        for k in range(int(rng.integers(1, 4))):
            start = int(rng.integers(150, 500)) if k == 0 else int(rng.integers(150, N - 40))
            lost[start:start + int(rng.integers(1, 31))] = True
        return AuditCase(**common, **lead, recursion="none", alignment=int(rng.integers(0, 2)),
                         header=str(rng.choice(["open-loop", "lead", "none"])), ga_s=ga,
                         rows=tuple(int(k) for k in np.flatnonzero(~lost)))
    if base.startswith("int:"):
        recursion, d = base[4:].split("_d")
        return AuditCase(**common, **lead, recursion=recursion, alignment=int(d), header="none")
    if base == "session":
        return AuditCase(**common, **lead, recursion="trunc", alignment=0, header="open-loop")
    if base == "lie:accel_int":
        return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round", "float-trunc", "float-round"])),
                         alignment=int(rng.integers(0, 2)), header="open-loop", ga_s=GA_S)
    if base == "lie:sent":
        return AuditCase(**common, **lead, recursion=str(rng.choice(["float-trunc", "float-round"])),
                         alignment=int(rng.integers(0, 2)), header="open-loop")
    if base == "honest:p":
        return AuditCase(**{**common, "header_kp": kp}, **p_law, recursion=str(rng.choice(["none", "trunc"])),
                         alignment=int(rng.integers(0, 2)), header="p")
    if base == "swap":
        pair = ("u", "v") if rng.random() < 0.5 else ("theta", "a")
        return _true_or_no_header(rng, common, p_law, lead, kp, swap=pair)
    if base == "rows":
        ticks = np.arange(N)
        if rng.random() < 0.75:  # rows lost while the hub moves (after the step, in the sine or sweep)
            lost = np.zeros(N, dtype=bool)
            for _ in range(int(rng.integers(1, 4))):
                start = int(rng.integers(20, 500))
                lost[start:start + int(rng.integers(1, 31))] = True
            ticks = ticks[~lost]
        else:  # a block of rows written again
            start, width = int(rng.integers(20, 500)), int(rng.integers(2, 31))
            ticks = np.r_[ticks[:start + width], ticks[start:start + width], ticks[start + width:]]
        rows = tuple(int(k) for k in ticks)
        return _true_or_no_header(rng, common, p_law, lead, kp, rows=rows)
    if base == "a_unit":
        return _true_or_no_header(rng, common, p_law, lead, kp, a_unit=str(rng.choice(sorted(A_UNITS))))
    if base == "v_unit":
        unit = str(rng.choice(sorted(V_UNITS)))
        if rng.random() < 0.5:
            return AuditCase(**{**common, "header_kp": kp}, **p_law, recursion="trunc",
                             alignment=int(rng.integers(0, 2)), header="p", v_unit=unit)
        return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round", "none"])),
                         alignment=int(rng.integers(0, 2)), header="lead", v_unit=unit)
    if base == "printed":  # MATLAB's csvwrite (5 significant digits) or C's %g (6)
        return AuditCase(**common, **lead, recursion="none", alignment=int(rng.integers(0, 2)),
                         header=str(rng.choice(["lead", "open-loop"])), digits=int(rng.choice([5, 6])))
    if base == "sign":  # θ written negated under a true header, none, or an open-loop one
        if rng.random() < 0.25:
            return AuditCase(**common, **lead, recursion="trunc", alignment=int(rng.integers(0, 2)),
                             header="open-loop", negate=True)
        return _true_or_no_header(rng, common, p_law, lead, kp, negate=True)
    if base == "double":  # the session's lie and one column fault beside it
        fault = str(rng.choice(["v_unit", "negate", "swap", "digits"]))
        hidden = {"v_unit": {"v_unit": str(rng.choice(sorted(V_UNITS)))}, "negate": {"negate": True},
                  "swap": {"swap": ("u", "v")}, "digits": {"digits": int(rng.choice([5, 6]))}}[fault]
        return AuditCase(**common, **lead, recursion="none" if fault == "digits" else "trunc",
                         alignment=int(rng.integers(0, 2)), header="open-loop", **hidden)
    if base == "lie:swap":  # a closed-loop header that lies (a P's kp, a lead's pole) over two columns swapped
        pair = ("u", "v") if rng.random() < 0.5 else ("theta", "a")
        if rng.random() < 0.5:
            kp = float(rng.choice([g for g in P_GAINS if g != HEADER_KP]))
            p_law.update(kp=kp, design_text=f"P, kp = {kp:g}")
            return AuditCase(**{**common, "header_kp": HEADER_KP}, **p_law, recursion=str(rng.choice(["none", "trunc"])),
                             alignment=int(rng.integers(0, 2)), header="p", swap=pair)
        zz, pp = 2 * math.pi * 5, 2 * math.pi * float(rng.choice(OTHER_POLES_HZ))
        kk = 5.0 * pp / zz
        return AuditCase(**common, law="lead", kp=None, num_s=(kk, kk * zz), den_s=(1.0, pp),
                         design_text=_lead_text(kk, zz, pp, hz=True), recursion="none", alignment=1, header="lead",
                         swap=pair)
    if base == "lie:column":  # a closed-loop header that lies (a P's kp, a lead's pole) over one column fault
        fault = str(rng.choice(["v_unit", "v_zero", "theta_zero", "u_unit"]))
        hidden = {"v_unit": {"v_unit": str(rng.choice(sorted(V_UNITS)))}, "v_zero": {"v_zero": float(rng.choice(V_ZEROS))},
                  "theta_zero": {"theta_zero": float(rng.integers(5, 400)) * float(rng.choice([-1.0, 1.0]))},
                  "u_unit": {"u_unit": str(rng.choice(sorted(U_UNITS)))}}[fault]
        recursion = str(rng.choice(["trunc", "round"] if fault == "v_unit" else ["none", "trunc", "round"]))
        if fault != "v_unit" and rng.random() < 0.5:  # a P's v in another unit is another kp as much: a lead's
            kp = float(rng.choice([g for g in P_GAINS if g != HEADER_KP]))
            p_law.update(kp=kp, design_text=f"P, kp = {kp:g}")
            return AuditCase(**{**common, "header_kp": HEADER_KP}, **p_law, recursion=recursion, alignment=1,
                             header="p", **hidden)
        zz, pp = 2 * math.pi * 5, 2 * math.pi * float(rng.choice(OTHER_POLES_HZ))
        kk = 5.0 * pp / zz
        return AuditCase(**common, law="lead", kp=None, num_s=(kk, kk * zz), den_s=(1.0, pp),
                         design_text=_lead_text(kk, zz, pp, hz=True), recursion=recursion, alignment=1, header="lead",
                         **hidden)
    if base == "rows:column":  # rows lost beside one column fault, under a true header
        lost = np.zeros(N, dtype=bool)
        for _ in range(int(rng.integers(1, 4))):
            start = int(rng.integers(20, 500))
            lost[start:start + int(rng.integers(1, 31))] = True
        fault = str(rng.choice(["negate", "swap", "v_unit"]))
        hidden = dict(rows=tuple(int(k) for k in np.flatnonzero(~lost)))
        hidden.update({"negate": {"negate": True}, "v_unit": {"v_unit": str(rng.choice(sorted(V_UNITS)))},
                       "swap": {"swap": ("u", "v") if rng.random() < 0.5 else ("theta", "a")}}[fault])
        which = rng.random()
        if which < 1 / 3:
            return AuditCase(**{**common, "header_kp": kp}, **p_law, recursion="trunc",
                             alignment=int(rng.integers(0, 2)), header="p", **hidden)
        if which < 2 / 3:
            return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round"])),
                             alignment=int(rng.integers(0, 2)), header="lead", **hidden)
        p, z = 2 * math.pi * 20, 2 * math.pi * 5
        thesis = dict(law="lead", kp=None, num_s=(5 * p / z, 5 * p), den_s=(1.0, p),
                      design_text=_lead_text(5 * p / z, z, p, hz=True))
        return AuditCase(**common, **thesis, recursion="none", alignment=int(rng.integers(0, 2)), header="lead",
                         ga_s=GA_S, **hidden)
    if base == "pair":  # two column faults at once: a swap beside θ negated, or beside v in volts
        pair = ("u", "v") if rng.random() < 0.5 else ("theta", "a")
        if rng.random() < 0.5:
            return _true_or_no_header(rng, common, p_law, lead, kp, swap=pair, negate=True)
        unit = str(rng.choice(sorted(V_UNITS)))
        if rng.random() < 0.5:
            return AuditCase(**{**common, "header_kp": kp}, **p_law, recursion="trunc",
                             alignment=int(rng.integers(0, 2)), header="p", v_unit=unit, swap=pair)
        return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round"])),
                         alignment=int(rng.integers(0, 2)), header="lead", v_unit=unit, swap=pair)
    if base == "v_zero":  # v written as an unsigned DAC code, about its midpoint
        zero = float(rng.choice(V_ZEROS))
        if rng.random() < 0.25:  # so written by the lab's session (an open-loop header on a lead on the integer)
            return AuditCase(**common, **lead, recursion="trunc", alignment=int(rng.integers(0, 2)),
                             header="open-loop", v_zero=zero)
        return _true_or_no_header(rng, common, p_law, lead, kp, v_zero=zero)
    if base == "u_unit":  # the reference written in degrees or radians of the hub
        unit = str(rng.choice(sorted(U_UNITS)))
        if rng.random() < 0.25:  # by the lab's session (an open-loop header on a lead on the integer)
            return AuditCase(**common, **lead, recursion="trunc", alignment=int(rng.integers(0, 2)),
                             header="open-loop", u_unit=unit)
        return _true_or_no_header(rng, common, p_law, lead, kp, u_unit=unit)
    if base == "theta_zero":  # θ written as the encoder read it, from an earlier run's count
        zero = float(rng.integers(5, 400)) * float(rng.choice([-1.0, 1.0]))
        if rng.random() < 0.25:  # by the lab's session (an open-loop header on a lead on the integer)
            return AuditCase(**common, **lead, recursion="trunc", alignment=int(rng.integers(0, 2)),
                             header="open-loop", theta_zero=zero)
        return _true_or_no_header(rng, common, p_law, lead, kp, theta_zero=zero)
    if base == "zero:column":  # θ from an earlier run's count, beside θ negated or u and v swapped
        zero = float(rng.integers(5, 400)) * float(rng.choice([-1.0, 1.0]))
        hidden = {"negate": True} if rng.random() < 0.5 else {"swap": ("u", "v")}
        if rng.random() < 0.25:  # by the lab's session (an open-loop header on a lead on the integer)
            return AuditCase(**common, **lead, recursion="trunc", alignment=int(rng.integers(0, 2)),
                             header="open-loop", theta_zero=zero, **hidden)
        return _true_or_no_header(rng, common, p_law, lead, kp, theta_zero=zero, **hidden)
    if base == "zero:command":  # θ from an earlier run's count, beside v in volts or about a DAC code's midpoint
        zero = float(rng.integers(5, 400)) * float(rng.choice([-1.0, 1.0]))
        hidden = ({"v_zero": float(rng.choice(V_ZEROS))} if rng.random() < 0.5 else
                  {"v_unit": str(rng.choice(sorted(V_UNITS)))})
        which = rng.random()
        if which < 0.25:  # by the lab's session (an open-loop header on a lead on the integer)
            return AuditCase(**common, **lead, recursion="trunc", alignment=int(rng.integers(0, 2)),
                             header="open-loop", theta_zero=zero, **hidden)
        if "v_unit" in hidden and which < 0.5:  # as "v_unit"'s: a float P's v in volts is another kp as much
            return AuditCase(**{**common, "header_kp": kp}, **p_law, recursion="trunc",
                             alignment=int(rng.integers(0, 2)), header="p", theta_zero=zero, **hidden)
        if "v_zero" in hidden:
            return _true_or_no_header(rng, common, p_law, lead, kp, theta_zero=zero, **hidden)
        return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round"])),
                         alignment=int(rng.integers(0, 2)), header="lead" if which < 0.75 else "none",
                         theta_zero=zero, **hidden)
    if base in ("three:columns", "four:columns"):  # "zero:command"'s two faults, θ negated or u and v swapped too
        zero = float(rng.integers(5, 400)) * float(rng.choice([-1.0, 1.0]))
        hidden = ({"v_zero": float(rng.choice(V_ZEROS))} if rng.random() < 0.5 else
                  {"v_unit": str(rng.choice(sorted(V_UNITS)))})
        more = {"negate": True} if rng.random() < 0.5 else {"swap": ("u", "v")}
        if base == "four:columns":  # both
            more = {"negate": True, "swap": ("u", "v")}
        if rng.random() < 0.5:
            return AuditCase(**{**common, "header_kp": kp}, **p_law, recursion="trunc",
                             alignment=int(rng.integers(0, 2)), header="p", theta_zero=zero, **hidden, **more)
        return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round"])),
                         alignment=int(rng.integers(0, 2)), header="lead", theta_zero=zero, **hidden, **more)
    if base == "three:open_loop":  # the same three under an open-loop header or none: the law from the data
        zero = float(rng.integers(5, 400)) * float(rng.choice([-1.0, 1.0]))
        more = {"negate": True} if rng.random() < 0.5 else {"swap": ("u", "v")}
        header = "open-loop" if rng.random() < 0.75 else "none"
        if rng.random() < 0.5:  # a P's v in volts is another kp as much: about a DAC code's midpoint only
            return AuditCase(**common, **p_law, recursion="trunc", alignment=int(rng.integers(0, 2)), header=header,
                             theta_zero=zero, v_zero=float(rng.choice(V_ZEROS)), **more)
        hidden = ({"v_zero": float(rng.choice(V_ZEROS))} if rng.random() < 0.5 else
                  {"v_unit": str(rng.choice(sorted(V_UNITS)))})
        return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round"])),
                         alignment=int(rng.integers(0, 2)), header=header, theta_zero=zero, **hidden, **more)
    if base == "a_zero":  # a written as read, the loop feeding Ga the reading less its zero
        p, z = 2 * math.pi * 20, 2 * math.pi * 5
        thesis = dict(law="lead", kp=None, num_s=(5 * p / z, 5 * p), den_s=(1.0, p),
                      design_text=_lead_text(5 * p / z, z, p, hz=True))
        zero = round(float(rng.uniform(0.5, 80.0)) * float(rng.choice([-1.0, 1.0])), 2)
        recursion = str(rng.choice(["none", "none", "trunc", "round", "float-trunc", "float-round"]))
        return AuditCase(**common, **thesis, recursion=recursion, alignment=int(rng.integers(0, 2)), header="lead",
                         ga_s=GA_S, a_zero=zero)
    if base == "lie:a_zero":  # the same, under an open-loop header or none, a lead and Ga of its own
        g, f = float(rng.choice(GA_GAINS)), float(rng.choice(GA_FREQUENCIES))
        (b1, b0), (_, a2, a1, a0) = GA_S
        ga = ((g * b1 * f, g * b0 * f * f), (1.0, a2 * f, a1 * f * f, a0 * f ** 3))  # g·Ga(s/f)
        zero = round(float(rng.uniform(0.5, 80.0)) * float(rng.choice([-1.0, 1.0])), 2)
        return AuditCase(**common, **lead, recursion="none", alignment=int(rng.integers(0, 2)),
                         header=str(rng.choice(["open-loop", "none"])), ga_s=ga, a_zero=zero)
    if base == "words":
        if rng.random() < 0.5:
            return AuditCase(**{**common, "header_kp": kp}, **p_law, recursion="trunc",
                             alignment=int(rng.integers(0, 2)), header="p", words=True)
        return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round"])),
                         alignment=int(rng.integers(0, 2)), header="lead", words=True)
    if base == "honest:lead_sent":
        return AuditCase(**common, **lead, recursion=str(rng.choice(["float-trunc", "float-round"])),
                         alignment=int(rng.integers(0, 2)), header="lead")
    return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round"])),
                     alignment=int(rng.integers(0, 2)), header="lead")  # honest:lead_int


def _true_or_no_header(rng: np.random.Generator, common: dict, p_law: dict, lead: dict, kp: float,
                       **hidden) -> AuditCase:
    """A case under a true header or none (the "swap" and "rows" classes): a third a P law
    under its P header, else a lead on the stored integer under its lead header or no header
    (the 2014 layout), with what the class hides (``hidden``: ``swap=`` or ``rows=``)."""
    which = rng.random()
    if which < 1 / 3:
        return AuditCase(**{**common, "header_kp": kp}, **p_law, recursion=str(rng.choice(["none", "trunc"])),
                         alignment=int(rng.integers(0, 2)), header="p", **hidden)
    return AuditCase(**common, **lead, recursion=str(rng.choice(["trunc", "round"])),
                     alignment=int(rng.integers(0, 2)), header="lead" if which < 2 / 3 else "none", **hidden)


def _quantize(x: float, recursion: str) -> float:
    if recursion == "trunc":
        return float(math.trunc(x))
    if recursion == "round":
        mag = abs(x)
        whole = math.floor(mag)
        whole += 1.0 if mag - whole >= 0.5 else 0.0
        return math.copysign(whole, x)
    return x


class LabController:
    """The lab's recursion: y = sat(Q(Σ b x − Σ a y)), its history the stored y; or, with a
    "float-" recursion, y = sat(Σ b x − Σ a y) remembered and Q(y) sent (and logged)."""

    def __init__(self, num, den, limit: float, recursion: str):
        self.b, self.a = [float(c) for c in num], [float(c) for c in den]
        self.limit, self.recursion = limit, recursion
        self.x = [0.0] * len(self.b)
        self.y = [0.0] * (len(self.a) - 1)

    def step(self, e: float) -> float:
        self.x = [e] + self.x[:-1]
        acc = sum(b * x for b, x in zip(self.b, self.x)) - sum(a * y for a, y in zip(self.a[1:], self.y))
        sent = self.recursion.startswith("float-")
        y = min(max(acc if sent else _quantize(acc, self.recursion), -self.limit), self.limit)
        if self.y:
            self.y = [y] + self.y[:-1]
        return _quantize(y, self.recursion[6:]) if sent else y


def reference(case: AuditCase, n: int = N) -> np.ndarray:
    """u[k] of a case, encoder counts: a step at tick 10, a 5 Hz sine or a "0-10 Hz" sweep
    (from 0.02 s), the sines truncated to whole counts as the lab's software did. The sweep is
    the lab's: sin(2π f(t) t) with f rising from 0 to 10 Hz over the run, whose instantaneous
    frequency 2 f(t) reaches 20 Hz, through the beam's second mode (the April 2009 session's
    "swept*-0-10hz" references: 50 sin(2π·2.5 t²), 20 Hz at 4 s)."""
    t = np.arange(n) * DT
    u = np.zeros(n)
    on = t >= 10 * DT
    if case.reference == "step":
        u[on] = case.amplitude
    elif case.reference == "sine":
        u[on] = np.trunc(case.amplitude * np.sin(2 * math.pi * 5.0 * (t[on] - t[on][0])))
    else:
        tt = t[on] - t[on][0]
        u[on] = np.trunc(case.amplitude * np.sin(2 * math.pi * (10.0 * tt / tt[-1]) * tt))
    return u


def simulate_audit_case(case: AuditCase, seed: int, substeps: int = 100, accel_noise: float = 0.3,
                        accel_bias: float = 0.0) -> Run:
    """One run of the case on the blind rig, as the lab's software ran it (its alignment);
    ``accel_bias``: counts the accelerometer reads over the tip's acceleration, fed back too."""
    eff = Effects.parse(case.effects)
    plant, a_gain = make_plant(eff, 4, substeps)
    amp = Amplifier(eff.saturation, eff.deadzone, eff.delay, eff.amp_offset)
    if case.law == "p":
        ctrl = LabController([case.kp], [1.0], case.limit, case.recursion)
    else:
        ctrl = LabController(*tustin(list(case.num_s), list(case.den_s), DT), case.limit, case.recursion)
    ga = None if case.ga_s is None else LabController(*tustin(*case.ga_s, DT), math.inf, case.ga_recursion)
    u = reference(case)
    rng = np.random.default_rng([seed, 26])
    noise = rng.normal(0.0, accel_noise, N)
    out = np.zeros((8, N))
    d = case.alignment
    for k in range(N):
        th, acc = plant.outputs()
        theta = encoder(th)
        a = math.floor(a_gain * acc + accel_bias + noise[k] + 0.5)
        out[2, k], out[3, k] = theta, a
        hat = u[k] if k < d or ga is None else float(u[k]) - ga.step(out[3, k - d])
        v = 0.0 if k < d else ctrl.step(hat - out[2, k - d])
        applied = amp(v)
        out[:, k] = (u[k], v, theta, a, hat, applied, th, plant.motor())
        plant.advance(applied)
    return Run(*out)


def header(case: AuditCase) -> list[str]:
    """The header lines the lab's software wrote (without newlines), the column line last."""
    if case.header == "open-loop":
        return ["#SLFR RTP OL_Test", COLUMNS]
    if case.header == "p":
        return ["#SLFR RTP P_control_Test", f"#kp={case.header_kp!r}", COLUMNS]
    if case.header == "lead":
        if case.name.startswith(("lie:lead_pole", "lie:swap", "lie:column")):
            num, den = gth_design()  # the thesis's lead; the data's has another pole
        else:
            num, den = tustin(list(case.num_s), list(case.den_s), DT)
        ga = ("[]", "[]")  # no accelerometer feedback named (a lie where the data hold one: "lie:accel_fb")
        if (case.a_zero is not None or case.ga_recursion != "none"
                or case.name.startswith("rows:column") and case.ga_s is not None):  # named
            ga = tuple(_coeffs(x) for x in tustin(*case.ga_s, DT))
        return ["#SLFR RTP Motor_Comp_w_accel_fb", f"#Gth num={_coeffs(num)}", f"#Gth den={_coeffs(den)}",
                f"#Ga num={ga[0]}", f"#Ga den={ga[1]}", COLUMNS_ACCEL]
    return []


WORD_COLUMNS = ("u", "v", "theta", "a", "theta_d_hat")
"""The signed columns a client may read as unsigned 16-bit words (the "words" class)."""


def as_words(sim: Run, written: tuple[str, ...] = WORD_COLUMNS) -> tuple[Run, tuple[str, ...]]:
    """The run with each whole-count signed column of ``written`` that goes negative written
    as an unsigned 16-bit word (x mod 65536), and the names of those columns."""
    cols = {}
    for name in written:
        x = np.asarray(getattr(sim, name), dtype=float)
        if np.all(x == np.round(x)) and np.any(x < 0):
            cols[name] = np.mod(x, 65536.0)
    return dataclasses.replace(sim, **cols), tuple(cols)


def format_audit_run(case: AuditCase, sim: Run) -> str:
    """The log text: the rig's ``#`` layout, or the 2014 layout (no header, columns
    ``Time (sec.) u theta accel v``) when the header names nothing."""
    lines = header(case)
    ticks = case.rows or range(N)
    if case.header == "none":
        lines = ["Time (sec.)\tu\ttheta\taccel\tv"]
        rows = ([k * DT, sim.u[k], sim.theta[k], sim.a[k], sim.v[k]] for k in ticks)
    else:
        accel = case.header == "lead"
        rows = ([k * DT, k, sim.u[k], sim.v[k], sim.theta[k], sim.a[k]] + ([sim.theta_d_hat[k]] if accel else [])
                for k in ticks)
    num = _num if case.digits is None else (lambda x: f"{x:.{case.digits}g}")
    lines += ["\t".join(num(float(x)) for x in row) for row in rows]
    return "\n".join(lines) + "\n"


def write_audit_case(folder: Path, name: str, seed: int) -> tuple[Path, AuditCase]:
    """Write one audit case's log (:func:`draw_case`, :func:`simulate_audit_case`).

    Parameters
    ----------
    folder : Path
        Created if missing.
    name : str
        A class of :data:`CLASSES`, optionally "+coulomb_friction".
    seed : int

    Returns
    -------
    (Path, AuditCase)
        The file, named like the lab's (``audit_<class>_<seed>_SLFR_RTP_<test>.txt``; no
        kp, amplitude or other claim in the name), and what it hides (with ``wrapped``, the
        columns written as words).
    """
    return write_case(folder, draw_case(name, seed), seed)


def write_case(folder: Path, case: AuditCase, seed: int) -> tuple[Path, AuditCase]:
    """Write one audit case's log as :func:`write_audit_case` does, for a case given (one no
    class draws; its noise from ``seed``)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    test = {"open-loop": "OL_Test", "p": "P_control_Test", "lead": "Motor_Comp_Gth", "none": "run"}[case.header]
    tag = case.name.replace(":", "-").replace("+", "-").replace("_", "-")  # no "kp_", "amp_" claims in the name
    path = folder / f"audit_{tag}_{seed}_SLFR_RTP_{test}.txt"
    sim = simulate_audit_case(case, seed)
    if case.words:
        sim, wrapped = as_words(sim, WORD_COLUMNS if case.header == "lead" else WORD_COLUMNS[:-1])
        case = dataclasses.replace(case, wrapped=wrapped)
    if case.a_unit is not None:  # a script's scaling, printed to 7 digits
        sim = dataclasses.replace(sim, a=np.array([float(f"{x:.7g}") for x in sim.a * A_UNITS[case.a_unit]]))
    if case.v_unit is not None:
        sim = dataclasses.replace(sim, v=np.array([float(f"{x:.7g}") for x in sim.v * V_UNITS[case.v_unit]]))
    if case.v_zero is not None:
        sim = dataclasses.replace(sim, v=np.asarray(sim.v, dtype=float) + case.v_zero)
    if case.u_unit is not None:
        sim = dataclasses.replace(sim, u=np.asarray(sim.u, dtype=float) * U_UNITS[case.u_unit])
    if case.theta_zero is not None:  # the loop took θ0 off; the script wrote the encoder's count
        sim = dataclasses.replace(sim, theta=np.asarray(sim.theta, dtype=float) + case.theta_zero)
    if case.a_zero is not None:  # the loop took a0 off; the script wrote the accelerometer's reading
        sim = dataclasses.replace(sim, a=np.asarray(sim.a, dtype=float) + case.a_zero)
    if case.negate:  # a script that wrote the loop's angle with the other sign
        sim = dataclasses.replace(sim, theta=-np.asarray(sim.theta, dtype=float))
        # as the words' wrapped columns: the fault is in the data only where it changed θ (a hub
        # friction held at 0 the whole run is the same column either sign)
        case = dataclasses.replace(case, negate=bool(np.any(sim.theta != 0)))
    if case.swap:
        first, second = case.swap
        sim = dataclasses.replace(sim, **{first: getattr(sim, second), second: getattr(sim, first)})
    path.write_text(format_audit_run(case, sim))
    return path, case
