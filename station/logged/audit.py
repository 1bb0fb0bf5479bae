"""The log audit: every claim a log makes, checked against its data before it is used.

DESIGN.md "Log audit": a log claims a controller (its header, or its file name's kp), an
alignment (our header), a reference (a step amplitude or a final u its file name or header
states, a run length), a sample time (our header's dt, the rig's 0.002 s) and the units of
its columns (t in s, θ in encoder counts). Each claim becomes an :class:`AuditClaim` with
what the header says, what the data say, a verdict ("confirmed", "contradicted", "unchecked"
when the log states nothing the data could check or the data cannot decide) and the
evidence in numbers; an :class:`Audit` holds them and where the controller came from.
A contradicted claim is said in one line before anything else (:meth:`Audit.lines`), and
the data's answer is what :class:`station.logged.LoggedRun` uses.

This module checks the claims that need no controller (:func:`reference_claims`, :func:`time_base`,
:func:`alignment_claim`); the controller's claim is :func:`station.logged.controller.identify_controller`'s,
since only replaying a law over the log decides it.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.logged.quantum import in_counts
from station.runlog import RunLog
from station.runlog.timebase import row_ticks

CLAIMS = ("controller", "alignment", "reference", "sample_time", "columns")
"""What a log can claim (DESIGN.md "Log audit")."""

VERDICTS = ("confirmed", "contradicted", "unchecked")
"""An audit's verdicts: the data agree, the data say otherwise, nothing the data could decide."""

SOURCES = ("header", "inferred", "inferred (header contradicted)")
"""Where a log's controller came from (``controller_source``; None: no controller)."""

ACCEL_DRIFT_WINDOW_S = 2.0
"""Window of :func:`accel_drift`, s."""

ACCEL_DRIFT_COUNTS = 10.0
"""A log's a column is no tip acceleration when its mean over some :data:`ACCEL_DRIFT_WINDOW_S`
window moves this far from its rest value, counts. That mean is a_gain times the tip's change
of speed over the window divided by its length: on the rig's logs at most 2.6 counts (a
swept sine of 75 counts), and 41 on a 2014 log whose a channel creeps from -66 to -26
counts with no accelerometer behind it."""

ACCEL_CLAIM = "a: tip acceleration"
"""What every log's a column claims (the header of its "columns" audit claim)."""


@dataclass(frozen=True)
class AuditClaim:
    """One claim of a log, checked against its data.

    Attributes
    ----------
    claim : str
        One of :data:`CLAIMS`.
    header : str
        What the log says (its header or file name; "not stated" when it says nothing).
    data : str
        What its data say.
    verdict : str
        One of :data:`VERDICTS`.
    evidence : str
        Words with numbers.
    """

    claim: str
    header: str
    data: str
    verdict: str
    evidence: str

    def __post_init__(self) -> None:
        if self.claim not in CLAIMS or self.verdict not in VERDICTS:
            raise ValueError(f"claim {self.claim!r} / verdict {self.verdict!r}: expected one of {CLAIMS} / {VERDICTS}")

    @property
    def line(self) -> str:
        """The one line a contradiction is said in: ``header: ...; data: ...``."""
        return f"header: {self.header}; data: {self.data}"

    def to_json(self) -> dict[str, str]:
        """``{"claim", "header", "data", "verdict", "evidence"}``."""
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Audit:
    """A log's claims checked against its data (:attr:`station.logged.LoggedRun.audit`).

    Attributes
    ----------
    claims : tuple of AuditClaim
        Controller first, then alignment, reference, sample time and columns.
    controller_source : str or None
        One of :data:`SOURCES`; None when no controller is known.
    """

    claims: tuple[AuditClaim, ...]
    controller_source: str | None

    @property
    def contradicted(self) -> tuple[AuditClaim, ...]:
        """The claims the data contradicted, in order."""
        return tuple(c for c in self.claims if c.verdict == "contradicted")

    @property
    def accel_is_tip(self) -> bool:
        """False when the data contradict the a column's claim to be a tip acceleration
        (:func:`accel_claims`): its fit and its weight in a diagnosis mean nothing."""
        return not any(c.header == ACCEL_CLAIM for c in self.contradicted)

    def of(self, claim: str) -> AuditClaim | None:
        """The audit's row for one claim (one of :data:`CLAIMS`), or None when the log made none.

        Parameters
        ----------
        claim : str

        Returns
        -------
        AuditClaim or None
        """
        return next((c for c in self.claims if c.claim == claim), None)

    def lines(self, skip: tuple[str, ...] = ()) -> list[str]:
        """One line per contradicted claim, e.g. ``"header: open loop; data: a lead
        3(s+13)/(s+20) ... at alignment 0, reproduces every logged v exactly"``.

        Parameters
        ----------
        skip : tuple of str, optional
            Headers of claims not to say (a diagnosis says the sensors' signs it decided over
            all its runs instead of each run's: :data:`station.logged.sensors.SESSION_HEADERS`).

        Returns
        -------
        list of str
        """
        return [c.line for c in self.contradicted if c.header not in skip]

    def to_json(self) -> list[dict[str, str]]:
        """DESIGN.md's ``"audit"`` list."""
        return [c.to_json() for c in self.claims]


NAMED_RUNS = 3
"""Most runs named beside a claim several of a diagnosis's runs (not all) share."""


def said_once(runs) -> list[str]:
    """The contradicted claims of several runs (a diagnosis's, a session's), each said once:
    ``"audit: 16 of 16 runs: header: open loop; data: ..."``, the runs named where some hold it
    and others do not (``"audit: 2 of 16 runs (step1.txt, step2.txt): ..."``, at most
    :data:`NAMED_RUNS` names), ``"audit: step1.txt: ..."`` where one run alone holds it.

    Parameters
    ----------
    runs : sequence of (str, sequence of str)
        Each run's name and its :meth:`Audit.lines`.

    Returns
    -------
    list of str
        In the order the claims were first met; empty when nothing was contradicted.
    """
    where: dict[str, list[str]] = {}
    for name, lines in runs:
        for line in lines:
            where.setdefault(line, []).append(name)
    out = []
    for line, names in where.items():
        if len(names) == 1:
            out.append(f"audit: {names[0]}: {line}")
            continue
        listed = "" if len(names) == len(runs) else " (" + ", ".join(names[:NAMED_RUNS]) + (
            f" and {len(names) - NAMED_RUNS} more" if len(names) > NAMED_RUNS else "") + ")"
        out.append(f"audit: {len(names)} of {len(runs)} runs{listed}: {line}")
    return out


# --- the file name's claims --------------------------------------------------------------

_NUMBER = r"(-?\d+(?:\.\d+)?)"
_FILE_CLAIMS = {
    "amp": re.compile(r"(?:^|_)amp[_=]" + _NUMBER + r"(?=_|$)"),
    "kp": re.compile(r"(?:^|_)kp[_=]" + _NUMBER + r"(?=_|$)"),
    "uend": re.compile(r"(?:^|_)uend=" + _NUMBER + r"(?=_|$)"),
    "stopn": re.compile(r"(?:^|_)stopn=" + _NUMBER + r"(?=_|$)"),
    "duration": re.compile(r"(?:^|_)duration[_=]" + _NUMBER + r"(?=_|$)"),
}


def file_name_claims(path: str | Path) -> dict[str, list[float]]:
    """What a lab's file name states, by the rig's naming (``..._kp_2_...``, ``amp=100``,
    ``uend=77``, ``stopn=20000``, ``duration_1000``).

    Parameters
    ----------
    path : str or Path
        The log's path (its stem is read).

    Returns
    -------
    dict
        "amp" (reference amplitude, counts), "kp" (P gain), "uend" (the last u), "stopn" and
        "duration" (the run's samples: the thesis's 2 s steps are ``duration_1000``) -> the
        distinct values stated, in order; absent keys are not stated.
    """
    stem = Path(path).name
    stem = stem[:-4] if stem.lower().endswith(".txt") else stem
    out: dict[str, list[float]] = {}
    for key, pattern in _FILE_CLAIMS.items():
        values = list(dict.fromkeys(float(m.group(1)) for m in pattern.finditer(stem)))
        if values:
            out[key] = values
    return out


# --- the reference -----------------------------------------------------------------------

def reference_claims(log: RunLog, reference) -> list[AuditClaim]:
    """The reference's claims (a step or sine amplitude, the final u, the run's length) against u.

    Parameters
    ----------
    log : RunLog
    reference : station.logged.reference.Reference
        What u is (:func:`station.logged.reference.classify_reference`).

    Returns
    -------
    list of AuditClaim
        One per claim the file name or our header makes ([] when none).
    """
    u = np.asarray(log.data["u"], dtype=float)
    if not u.size or not np.all(np.isfinite(u)):
        return []
    out = []
    stated = file_name_claims(log.path)
    meta_ref = log.meta.get("reference") if log.format == "station" else None
    amps = [("file name", a) for a in stated.get("amp", [])]
    if isinstance(meta_ref, dict) and isinstance(meta_ref.get("amplitude"), (int, float)):
        amps.append((f"{meta_ref.get('kind', 'reference')} of the header", float(meta_ref["amplitude"])))
    peak = float(np.max(np.abs(u)))
    for where, amp in amps:
        if reference.is_step:
            ok = amp in (reference.amplitude, reference.height)  # from a held position: its end or its height
            data = f"a step of {reference.height:g}{reference.held_words} at tick {reference.step_tick}"
        else:  # a sine or pulse: its peak (a truncated sine's is up to one count lower)
            ok = abs(amp) - 1.0 - 0.03 * abs(amp) <= peak <= abs(amp) * (1 + 1e-9)
            data = f"{reference.kind} reference, max |u| = {peak:g}"
        out.append(AuditClaim("reference", f"{where}: amplitude {amp:g}", data,
                              "confirmed" if ok else "contradicted",
                              f"u {'matches' if ok else 'does not match'} the stated amplitude {amp:g} "
                              f"(max |u| = {peak:g}, last u = {u[-1]:g})"))
    if isinstance(meta_ref, dict) and reference.is_step and isinstance(meta_ref.get("step_tick"), int):
        tick = meta_ref["step_tick"]
        ok = tick == reference.step_tick
        out.append(AuditClaim("reference", f"header: step at tick {tick}", f"step at tick {reference.step_tick}",
                              "confirmed" if ok else "contradicted", f"u first reaches its final value at tick "
                              f"{reference.step_tick}"))
    for uend in stated.get("uend", []):
        ok = u[-1] == uend
        out.append(AuditClaim("reference", f"file name: last u = {uend:g}", f"last u = {u[-1]:g}",
                              "confirmed" if ok else "contradicted", f"u[{u.size - 1}] = {u[-1]:g}"))
    ticks = row_ticks(log.data["n"])  # rows missing or repeated: the run's samples are its ticks
    span, every = (u.size, 1) if ticks is None else (int(ticks.max()) + 1, max(int(np.median(np.diff(ticks))), 1))
    for stopn in stated.get("stopn", []) + stated.get("duration", []):
        ok = 0 <= stopn - span <= 2 * (every - 1)  # every k-th tick kept: up to k - 1 not, before and after
        kept = f", one tick in {every} kept" if every > 1 else ""
        held = f"{u.size} rows" if ticks is None else f"{u.size} rows over {span} ticks (n jumps{kept})"
        out.append(AuditClaim("reference", f"file name: {stopn:g} samples", f"{span} samples",
                              "confirmed" if ok else "contradicted", f"the log holds {held}"))
    return out


def file_kp_claims(path: str | Path, controller_text: str, kp: float | None) -> list[AuditClaim]:
    """The P gain a lab's file name states (``..._kp_2_...``, ``kp=1.0``) against the
    controller the data confirmed or gave.

    Parameters
    ----------
    path : str or Path
    controller_text : str
        The controller used, in words (:func:`station.logged.controller.describe_controller`).
    kp : float or None
        Its gain when it is a P law, else None.

    Returns
    -------
    list of AuditClaim
        One per distinct kp the name states ([] when none).
    """
    out = []
    for value in file_name_claims(path).get("kp", []):
        ok = kp is not None and kp == value
        out.append(AuditClaim("controller", f"file name: kp = {value:g}", controller_text,
                              "confirmed" if ok else "contradicted",
                              f"the controller that reproduces the logged v is {controller_text}"))
    return out


# --- the accelerometer column ------------------------------------------------------------


def accel_drift(a, dt: float, rest: float = 0.0) -> float:
    """The largest |mean of a - rest| over any :data:`ACCEL_DRIFT_WINDOW_S` window, counts
    (0.0 for a shorter or non-finite a).

    Parameters
    ----------
    a : array_like, shape (N,)
        Accelerometer samples, counts.
    dt : float
        Sample time, s.
    rest : float
        The accelerometer's value at rest, counts.

    Returns
    -------
    float
    """
    w = int(round(ACCEL_DRIFT_WINDOW_S / dt))
    a = np.asarray(a, float) - rest
    if a.size < w or w < 1 or not np.all(np.isfinite(a)):
        return 0.0
    c = np.concatenate([[0.0], np.cumsum(a)])
    return float(np.max(np.abs(c[w:] - c[:-w])) / w)


ACCEL_BAND_HZ = (1.0, 40.0)
"""Band in which a tip acceleration shows (the beam's modes and the hub's motion), Hz."""

ACCEL_SIGNAL_RATIO = 2.0
"""An a column carries a tip acceleration when its :data:`ACCEL_BAND_HZ` RMS after the rest
is at least this many times its RMS at rest (floored at :data:`ACCEL_NOISE_FLOOR`): on the
rig's logs 4-33 (a ping, a swept sine), on the 2014 log with no accelerometer 0.4 (its noise
is the same all through: about 1)."""

ACCEL_NOISE_FLOOR = 0.5
"""The least band RMS at rest the signal test divides by, counts (a quantized still channel
reads 0.0-0.3)."""

ACCEL_REST_MIN = 10
"""Fewest samples at rest the signal test needs."""

ACCEL_BASELINE_CLAIM = "a: the tip's acceleration about a steady zero"
"""What a log's a column claims about its baseline (a contradicted baseline keeps a in use)."""


def accel_band(a, dt: float, rest_samples: int) -> tuple[float, float] | None:
    """a's RMS in :data:`ACCEL_BAND_HZ` after the rest, and at rest (floored at
    :data:`ACCEL_NOISE_FLOOR` where a is in counts, :func:`station.logged.quantum.in_counts`; a column in another unit
    is judged by its own noise), counts. With fewer than :data:`ACCEL_REST_MIN` samples at rest
    (a loop that answers a's first sample: Ga fed an unzeroed or dead channel), the band over the
    whole run and :data:`ACCEL_NOISE_FLOOR` as its noise: a still channel reads less (the 2014
    log without an accelerometer: 0.21 counts over the run), a live one on a moving beam far more
    (the thesis's lead + accelerometer step: 18.8). None for a run too short to filter or shorter than
    :data:`ACCEL_REST_MIN` past its rest or a band past the Nyquist frequency.

    Parameters
    ----------
    a : array_like, shape (N,)
        Accelerometer samples, counts.
    dt : float
        Sample time, s.
    rest_samples : int
        Samples at rest at the start of the run (before the first command).

    Returns
    -------
    (float, float) or None
        (band RMS after the rest, band RMS at rest), counts.
    """
    # lazy: start-up time (scipy's filters, loaded when a log's a is checked)
    from scipy.signal import butter, sosfiltfilt

    a = np.asarray(a, float)
    if a.size < rest_samples + ACCEL_REST_MIN or ACCEL_BAND_HZ[1] >= 0.5 / dt or not np.all(np.isfinite(a)):
        return None
    sos = butter(2, ACCEL_BAND_HZ, "bandpass", fs=1.0 / dt, output="sos")
    if a.size - 1 <= 3 * (2 * len(sos) + 1):  # shorter than sosfiltfilt's padding
        return None
    # half a count is the least a channel of whole counts reads; one in another unit has no count
    floor = ACCEL_NOISE_FLOOR if in_counts(a) else 0.0
    if rest_samples < ACCEL_REST_MIN:
        band = sosfiltfilt(sos, a[1:] - np.mean(a[1:]))
        return float(np.sqrt(np.mean(band ** 2))), floor
    band = sosfiltfilt(sos, a[1:] - np.mean(a[1:rest_samples]))  # row 0 of the 2014 layout is a zero
    at_rest = max(float(np.sqrt(np.mean(band[:rest_samples - 1] ** 2))), floor)
    return float(np.sqrt(np.mean(band[rest_samples - 1:] ** 2))), at_rest


def accel_signal(a, dt: float, rest_samples: int) -> float | None:
    """How far a's band RMS after the rest stands above its noise at rest (the ratio of
    :data:`ACCEL_SIGNAL_RATIO`, from :func:`accel_band`); None as :func:`accel_band`.

    Parameters
    ----------
    a : array_like, shape (N,)
        Accelerometer samples, counts.
    dt : float
        Sample time, s.
    rest_samples : int
        Samples at rest at the start of the run (before the first command).

    Returns
    -------
    float or None
    """
    band = accel_band(a, dt, rest_samples)
    return None if band is None else band[0] / band[1]


def accel_claims(a, dt: float, rest: float, rest_samples: int = 0) -> list[AuditClaim]:
    """The a column's claim to be a tip acceleration about a steady zero, checked by its drift
    (:func:`accel_drift`) and its signal (:func:`accel_signal`). A mean that moves
    :data:`ACCEL_DRIFT_COUNTS` or more from rest is no tip acceleration's; when the band
    :data:`ACCEL_BAND_HZ` then stands :data:`ACCEL_SIGNAL_RATIO` times above its noise at rest the
    channel still reads the tip (a ring-down, the run's motion) on a baseline that moves (the
    accelerometer's offset or drift, or a shift at an impact): its baseline claim is
    contradicted and a stays in use; else a is no tip acceleration (with no rest, the noise is
    :data:`ACCEL_NOISE_FLOOR`: :func:`accel_band`). A smaller drift decides nothing, so no claim
    is listed.

    Parameters
    ----------
    a : array_like, shape (N,)
        The logged a, counts.
    dt : float
        Sample time, s.
    rest : float
        a at rest before the first command, counts.
    rest_samples : int
        Samples at rest before the first command (0: unknown).

    Returns
    -------
    list of AuditClaim
        Empty, or one contradicted "columns" claim with header :data:`ACCEL_CLAIM` (a unused) or
        :data:`ACCEL_BASELINE_CLAIM` (a used).
    """
    drift = accel_drift(a, dt, rest)
    if drift < ACCEL_DRIFT_COUNTS:
        return []
    no_rest = rest_samples < ACCEL_REST_MIN
    zero = "0 (no rest to read its zero)" if no_rest else f"rest ({rest:.3g} counts)"
    moves = (f"a's mean over {ACCEL_DRIFT_WINDOW_S:g} s moves {drift:.0f} counts from {zero}: no "
             f"tip acceleration does that (at most 2.6 counts on the rig's logs; the bound is {ACCEL_DRIFT_COUNTS:g})")
    ratio = accel_signal(a, dt, rest_samples)
    noise = f"the most a still channel reads ({ACCEL_NOISE_FLOOR:g} counts; no rest)" if no_rest else "its noise at rest"
    if ratio is not None and ratio >= ACCEL_SIGNAL_RATIO:
        return [AuditClaim("columns", ACCEL_BASELINE_CLAIM,
                           f"the tip's acceleration on a baseline that moves {drift:.0f} counts (the accelerometer's "
                           f"offset or drift)", "contradicted",
                           f"{moves}; but its {ACCEL_BAND_HZ[0]:g}-{ACCEL_BAND_HZ[1]:g} Hz band stands {ratio:.0f} "
                           f"times above {noise}: the tip's acceleration on a moving baseline (a kept)")]
    why = ("too short a run to tell its noise from a signal" if ratio is None else
           f"its {ACCEL_BAND_HZ[0]:g}-{ACCEL_BAND_HZ[1]:g} Hz band is {ratio:.1f} times {noise} (a signal "
           f"stands {ACCEL_SIGNAL_RATIO:g} times above it)")
    return [AuditClaim("columns", ACCEL_CLAIM, "a is no tip acceleration (its accelerometer is not used)",
                       "contradicted", f"{moves}; {why}")]


# --- the alignment ------------------------------------------------------------------------

def alignment_claim(header: int | None, found: int | None, reproduced: bool, fmt: str,
                    tied: tuple[int, ...] = ()) -> AuditClaim | None:
    """Our header's alignment (the rig's headers state none) against the one the replay found.

    Parameters
    ----------
    header : int or None
        The alignment our header states.
    found : int or None
        The computational delay with which the controller reproduces the log (None: open
        loop or not replayed).
    reproduced : bool
        Whether the controller reproduces every logged v at ``found``.
    fmt : str
        The log's format ("station" or "rig").
    tied : tuple of int
        Every alignment at which the controller reproduces the log (several: the data cannot
        tell them apart, e.g. θ seldom changes between rows).

    Returns
    -------
    AuditClaim or None
        None when no closed-loop controller was replayed.
    """
    if found is None:
        return None
    said = "not stated" if header is None else f"alignment {header}"
    data = f"alignment {found} (v[k] from θ[k-{found}])" if found else "alignment 0 (v[k] from θ[k])"
    if not reproduced:
        return AuditClaim("alignment", said, data, "unchecked",
                          f"the controller does not reproduce the logged v at any alignment; {found} comes closest")
    if len(tied) > 1:
        alts = " and ".join(str(d) for d in tied)
        return AuditClaim("alignment", said, f"alignment {alts} alike", "unchecked",
                          f"the controller reproduces every logged v at alignments {alts}: the data cannot tell "
                          f"them apart (θ seldom changes between rows); {found} is used"
                          + ("" if header is None else ", as the header states" if header == found else ""))
    if header is None:
        why = "the rig's headers do not state it" if fmt == "rig" else "the header does not state it"
        return AuditClaim("alignment", said, data, "unchecked",
                          f"{why}; the data decide: the controller reproduces every logged v only at d = {found}")
    ok = header == found
    return AuditClaim("alignment", said, data, "confirmed" if ok else "contradicted",
                      f"the controller reproduces every logged v at d = {found}")

