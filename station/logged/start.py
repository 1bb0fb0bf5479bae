"""How a logged run starts: at rest at t = 0 (the lab zeroes the encoder and starts a test
still), or moving (a copy cut from a longer run, t re-zeroed), and where θ's zero is
(DESIGN.md "Log audit": the "reference" and "columns" claims of a run's start).

:func:`start_claims` checks the start; :class:`station.logged.LoggedRun` says it first when
contradicted, and a closed-loop run's model starts at rest at the logged first θ
(:func:`station.logged.simulate.simulate_log`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.logged.audit import AuditClaim
from station.logged.reference import held_at

START_WINDOW_S = 0.05
"""The start window, s: the rows before the first change of command, at most this long."""

START_MIN_ROWS = 3
"""Fewest rows of the start window (a command from row 0 cannot move the hub sooner)."""

EARLY_COMMAND = 100.0
"""A command, DAC counts, after which the rig's hub at rest moves its first encoder count
:data:`FIRST_COUNT_ROWS` rows later (the thesis's P step: its command of 100 logged at row 50,
θ's first count at row 53; the lead step's 200 at row 10, its count at row 12). From rest the
angle grows as the command times t²: under v, sqrt(100/|v|) times as many rows, and on an
encoder of s times the counts 1/sqrt(s) as many."""

FIRST_COUNT_ROWS = 3.0
"""Rows from a command of :data:`EARLY_COMMAND` to the hub's first count, from rest."""

EARLY_SHARE = 0.7
"""θ's first count before this share of the rows a hub at rest needs (:func:`earliest_count_row`)
is an earlier motion: half the acceleration's margin (0.7² ≈ 0.5) for a rig stronger or
lighter than the rig's."""

ACCEL_QUIET_COUNTS = 8.0
"""Largest peak-to-peak of a over the start window of a run at rest, counts (noise 0.3 std;
a beam ringing from an earlier motion swings tens of counts)."""

REST_ROWS = 10
"""Fewest rows at rest before the first command (:func:`rest_rows`) a zero read from the rest
needs: the open-loop sensor check, v's zero, θ's and a's
(:mod:`station.logged.columns`, :mod:`station.logged.sensor_zeros`)."""


def rest_rows(u, theta) -> int:
    """The rows at rest before the first command: u and θ unchanged from row 0 (v may move
    there: an accelerometer feedback on a's noise; no law commands anything else).

    Parameters
    ----------
    u, theta : array_like, shape (N,)
        Reference and hub angle, encoder counts.

    Returns
    -------
    int
        The first row where u or θ differs from its row 0 (N when neither ever does).
    """
    u, theta = np.asarray(u, dtype=float), np.asarray(theta, dtype=float)
    moved = np.flatnonzero((u != u[0]) | (theta != theta[0]))
    return int(moved[0]) if moved.size else int(theta.size)


START_CLAIM = "the run starts at rest at t = 0"
"""What every log claims about its start (the lab zeroes the encoder and starts a test at rest)."""

ZERO_CLAIM = "θ: 0 at the start (the encoder zeroed before a closed-loop run)"
"""What a closed-loop log claims about θ's zero (the loop's error is u - θ)."""


@dataclass(frozen=True)
class Start:
    """How a run starts (:func:`start_claims`).

    Attributes
    ----------
    claims : tuple of AuditClaim
    at_rest : bool or None
        True: still over the start window; False: moving (a copy cut from a longer run);
        None: undecided (too short a window under a constant command).
    theta0 : float
        θ at the start, encoder counts.
    """

    claims: tuple[AuditClaim, ...]
    at_rest: bool | None
    theta0: float


def earliest_count_row(v, encoder_scale: float = 1.0) -> float:
    """The soonest row a hub at rest at row 0 can move its first encoder count under the commands
    ``v`` (those logged before that row): :data:`EARLY_SHARE` of :data:`FIRST_COUNT_ROWS`
    under :data:`EARLY_COMMAND`, sqrt(EARLY_COMMAND / max |v|) times as many under another
    (the angle from rest grows as the command times t²), 1/sqrt(|encoder_scale|) as many on
    a finer encoder: 2.1 rows under 100, 1.5 under 200, 3.8 under 30.

    Parameters
    ----------
    v : array_like, shape (K,)
        Commands, DAC counts (NaN where not logged: taken as :data:`EARLY_COMMAND`).
    encoder_scale : float, default 1.0

    Returns
    -------
    float
        Rows; ``inf`` under commands of 0 (no command moves the hub).
    """
    v = np.asarray(v, float)
    top = float(np.max(np.abs(v))) if v.size and np.all(np.isfinite(v)) else EARLY_COMMAND
    if top == 0.0:
        return np.inf
    return EARLY_SHARE * FIRST_COUNT_ROWS * np.sqrt(EARLY_COMMAND / top / max(abs(encoder_scale), 1e-9))


def start_window(u, v) -> int:
    """Rows at the start under the run's first command: before u or v first changes from
    row 0's value, at most :data:`START_WINDOW_S` (0.05 s at the rig's rate: 25 rows).

    Parameters
    ----------
    u, v : array_like, shape (N,)
        Reference and command (NaN where not logged: not used).

    Returns
    -------
    int
    """
    first = []
    for x in (u, v):
        x = np.asarray(x, float)
        if x.size and np.all(np.isfinite(x)):
            moved = np.flatnonzero(x != x[0])
            first.append(int(moved[0]) if moved.size else x.size)
    return min(first) if first else 0


def start_claims(theta, a, u, v, dt: float, closed: bool, accel_is_tip: bool, remembered: bool = False,
                 accel_gain: float = 1.0, encoder_scale: float = 1.0) -> Start:
    """Check that the run starts at rest at t = 0, and where θ's zero is.

    Under the first command (:func:`start_window`, :data:`START_WINDOW_S` at most) a hub at rest
    stays on one count and the accelerometer reads noise (peak-to-peak at most
    :data:`ACCEL_QUIET_COUNTS`): θ changing there while the command is 0, or sooner than the
    commands before it could move a hub at rest a count (:func:`earliest_count_row`: a copy
    cut 50 rows after the thesis's P step moves a count at row 3 under a command of 30, where
    a hub at rest needs 5.5 rows, 3.8 with the margin), or a swinging before the first command
    of a count, is an earlier motion still going on (a copy cut from a longer run, t
    re-zeroed): "reference"
    contradicted (the model starts at rest: the start of its fit is that motion's). A start at
    rest off θ = 0 (the encoder not zeroed) contradicts a closed loop's zero ("columns": the
    loop's error was u - θ from that θ, and the model starts there); in open loop θ is compared
    relative to its first sample and a start off 0 is only said in the evidence.

    Parameters
    ----------
    theta, a, u, v : array_like, shape (N,)
        The log's columns (u NaN where not logged).
    dt : float
        Sample time, s.
    closed : bool
        Whether the run was closed loop.
    accel_is_tip : bool
        Whether a reads the tip (its swings count).
    remembered : bool
        The controller's law reproduces the log only with its first rows of memory taken as
        logged (:attr:`station.logged.controller.ControllerId.cut`): a copy cut from a longer
        run, its hub perhaps at rest.
    accel_gain : float, default 1.0
        The accelerometer's gain decided from the run's data (:attr:`station.logged.LoggedRun.sensors`):
        its noise at rest is that many times the rig's, and so is the quiet peak-to-peak (an
        accelerometer at 6x the model's a swung 18 counts at rest over the thesis's lead step's
        first 10 rows).
    encoder_scale : float, default 1.0
        Measured / modelled encoder counts decided from the data (a 4096-count encoder: 4):
        its first count comes sooner (:func:`earliest_count_row`).

    Returns
    -------
    Start
    """
    theta = np.asarray(theta, float)
    a = np.asarray(a, float)
    v = np.asarray(v, float)
    if theta.size < START_MIN_ROWS or not np.all(np.isfinite(theta[:START_MIN_ROWS])):
        return Start((), None, 0.0)
    cap = max(START_MIN_ROWS, int(round(START_WINDOW_S / dt)))
    w = max(min(start_window(u, v), cap), min(START_MIN_ROWS, theta.size))
    th0 = float(theta[0])
    still = bool(np.all(theta[:w] == th0))
    quiet = ACCEL_QUIET_COUNTS * max(1.0, abs(accel_gain))
    # a's swing counts before the first command of a count or more: a command swings the beam at once
    commanded = (np.flatnonzero(np.abs(v[:w]) >= 1.0) if v.size >= w and np.all(np.isfinite(v[:w]))
                 else np.array([], int))
    z = int(commanded[0]) if commanded.size else w
    swing = (float(np.ptp(a[1:z])) if accel_is_tip and z > 2 and np.all(np.isfinite(a[1:z])) else 0.0)
    idle = v.size >= w and np.all(np.isfinite(v[:w])) and np.all(v[:w] == 0)
    span = f"the first {w} rows ({w * dt:g} s, before the command first changes)"
    moved = np.flatnonzero(theta[:max(w, cap)] != th0)
    first = int(moved[0]) if moved.size else None
    soonest = None if first is None else earliest_count_row(v[:first], encoder_scale)
    early = first is not None and first < soonest  # sooner than the commands before it move a hub at rest
    if early and first >= w:  # the window ends at the command's first change: θ's first count after it
        w, still = first + 1, False
        span = f"the first {w} rows ({w * dt:g} s)"
    claims = []
    if remembered and still and swing <= quiet:
        claims.append(AuditClaim(
            "reference", START_CLAIM, "cut from a longer run (at rest, the controller's memory not)", "contradicted",
            f"the controller's law reproduces the logged v only with its first rows of memory taken as logged (the "
            f"earlier run's); θ keeps one count over {span}"))
        at_rest = False
    elif (not still and (idle or early)) or swing > quiet:
        what = []
        if not still:
            top = np.max(np.abs(v[:first]), initial=0.0) if early else 0.0
            what.append(f"θ moves {np.ptp(theta[:w]):g} counts" + (
                f" (its first count at row {first}: a hub at rest under commands up to {top:g} moves one no "
                f"sooner than row {soonest:.2g})" if early else ""))
        if swing > quiet:
            what.append(f"a swings {swing:g} counts")
        claims.append(AuditClaim(
            "reference", START_CLAIM, "moving at t = 0 (a copy cut from a longer run)", "contradicted",
            f"over {span} {' and '.join(what)}{' with v = 0' if idle else ''}: an earlier motion still going on "
            f"(at rest θ keeps one count and a's noise stays within {quiet:g} counts); the model "
            f"starts at rest, so the start of its fit is that motion's"))
        at_rest = False
    elif not still:
        claims.append(AuditClaim("reference", START_CLAIM, "undecided", "unchecked",
                                 f"θ moves over {span} under a command from row 0: a motion it started or an "
                                 f"earlier one"))
        at_rest = None
    else:
        at_rest = True
        counts = f"{th0:g} count" + ("" if abs(th0) == 1 else "s")
        off = "" if th0 == 0 else (f"; θ starts at {counts} (the encoder not zeroed"
                                   + ("): the loop's error was u - θ from there" if closed else
                                      "; open loop: θ compared relative to its first sample)"))
        claims.append(AuditClaim("reference", START_CLAIM, "at rest at t = 0", "confirmed",
                                 f"θ keeps one count and a's noise stays within {quiet:g} counts over "
                                 f"{span}{off}"))
    u = np.asarray(u, float)
    held = closed and u.size > 0 and held_at(float(u[0]), th0)  # a step from a held position
    if closed and th0 != 0 and at_rest:
        claims.append(AuditClaim("columns", ZERO_CLAIM, f"θ starts at {counts}" + (
            f", held at u = {float(u[0]):g}" if held else " (the encoder not zeroed)"),
            "unchecked" if held else "contradicted", f"θ[0] = {th0:g}: the controller's error was u - θ from there; "
            f"the model starts at rest at θ = {th0:g}" + ("; a run from a held position says nothing of where the "
                                                           "encoder was zeroed" if held else "")))
    return Start(tuple(claims), at_rest, th0)
