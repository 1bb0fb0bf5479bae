"""Logs like the lab's archives: hub-held beam tests, copies cut from a longer run,
downsampled, with columns dropped, an encoder that was not zeroed, an unplugged accelerometer.

From DESIGN.md ("The rig", "Timing and log rows", "Log audit") and the lab's published
archives' layouts alone, importing nothing from the station. Each writer returns the path
and what the log hides (:class:`Hidden`):

- :func:`write_beam_test`: the hub held (motor and base still), the beam released from a
  deflection or struck mid-span; the logged u = v steps to a level the held motor never
  applies; θ a constant that was not zeroed; the accelerometer with the tip's acceleration
  (the generator's FEM, held) on a baseline that is not zeroed, drifts back toward zero
  (a stab), or jumps at the strike and recovers (a shock);
- :func:`write_cut`: a run of the blind rig (:func:`tests.blind.rig.simulate`) cut from
  row ``start`` on, t re-zeroed, θ and a as logged (the lab's ``_trunc`` copies);
- :func:`write_copy`: a run re-written as a cut-down copy: ``t v theta a`` (no n, no u),
  every ``every``-th row (the lab's ``_downsampled``);
- :func:`write_unzeroed`: a closed-loop P step whose encoder read ``theta0`` at rest;
- :func:`write_unplugged`: a run whose a column is an unplugged input (noise and a creep);
- :func:`write_unpowered`: an open-loop pulse the amplifier never applied.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.linalg import expm

from tests.blind.fem import ROOT, Params, assemble, beta_for_damping, held_first_mode, tip_w
from tests.blind.generator import COLUMNS, _num, format_run, header, reference
from tests.blind.rig import DT, Run, simulate


@dataclass(frozen=True)
class Hidden:
    """What an archive-like log hides.

    Attributes
    ----------
    kind : str
        "held", "cut", "copy", "unzeroed", "unplugged", "unpowered" or "kept_ticks".
    moving_at_start : bool
        The run was moving at its first row (cut after the motion began).
    theta0 : float
        θ at the first row, encoder counts.
    dt : float
        The copy's sample time, s.
    f1_hz, zeta1 : float or None
        A held beam's first mode.
    accel_tip : bool
        Whether a reads the tip's acceleration.
    extra : dict
        Anything else (the baseline's kind, the cut row, ...).
    """

    kind: str
    moving_at_start: bool = False
    theta0: float = 0.0
    dt: float = DT
    f1_hz: float | None = None
    zeta1: float | None = None
    accel_tip: bool = True
    extra: dict = field(default_factory=dict)


def _rig_text(u, v, theta, a, dt: float = DT, head: tuple[str, ...] = ("#SLFR RTP OL_Test", COLUMNS)) -> str:
    rows = ("\t".join(_num(float(x)) for x in (k * dt, k, u[k], v[k], theta[k], a[k])) for k in range(len(u)))
    return "\n".join([*head, *rows]) + "\n"


# --- hub-held beam tests -------------------------------------------------------------------

def held_beam(event: str, n: int, t_event: float, zeta: float = 0.005, n_elements: int = 4,
              size: float = 0.02) -> tuple[np.ndarray, float, float]:
    """The tip's lateral acceleration (m/s^2, shape (n,)) of the beam with motor and base held:
    released at ``t_event`` from a static tip deflection of ``size`` m ("release"), or struck
    mid-span then with an impulse giving that node ``size`` * 100 m/s ("strike"); and the first
    mode (Hz, damping ratio)."""
    p = Params()
    beta = beta_for_damping(p, zeta, n_elements)
    m = assemble(p, n_elements, beta)
    free = slice(ROOT, None)
    M, C, K = m.M[free, free], m.C[free, free], m.K[free, free]
    nd = M.shape[0]
    minv = np.linalg.inv(M)
    A = np.block([[np.zeros((nd, nd)), np.eye(nd)], [-minv @ K, -minv @ C]])
    tip = tip_w(n_elements) - ROOT
    x0 = np.zeros(2 * nd)
    if event == "release":
        force = np.zeros(nd)
        force[tip] = 1.0
        q = np.linalg.solve(K, force)
        x0[:nd] = q * size / q[tip]
    else:  # an impulse on the middle node's lateral DOF
        mid = tip_w(max(1, n_elements // 2)) - ROOT
        kick = np.zeros(nd)
        kick[mid] = 1.0
        qd = minv @ kick
        x0[nd:] = qd * (100.0 * size) / qd[mid]
    step = expm(A * DT)
    out = np.zeros(n)
    x = x0.copy()
    for k in range(n):
        if k * DT >= t_event:
            out[k] = (A @ x)[nd + tip]
            x = step @ x
    f1, z1 = held_first_mode(p, n_elements, beta)
    return out, f1, z1


def write_beam_test(folder: Path, seed: int, event: str = "release", baseline: str = "steady",
                    level: float = 77.0, theta0: float = 3182.0, seconds: float = 10.0) -> tuple[Path, Hidden]:
    """A hub-held beam test as the lab logged it (``..._SLFR_RTP_OL_Test_uend=LEVEL.txt``).

    Parameters
    ----------
    folder : Path
    seed : int
        The accelerometer's noise and the event's time.
    event : {"release", "strike"}
    baseline : {"steady", "offset", "stab", "shock"}
        The accelerometer at rest: zeroed (-2 counts, as the 2009 rig's), not zeroed (an
        offset of 20-130 counts), drifting back from such an offset (time constant 8-15 s),
        or a jump of 80-150 counts at the strike recovering the same way.
    level : float
        The logged u = v after tick 50, DAC counts (never applied: the hub is held).
    theta0 : float
        θ all through, encoder counts.
    seconds : float
        The run's length.
    """
    rng = np.random.default_rng([seed, 2609])
    n = int(round(seconds / DT))
    t_event = 1.0 + float(rng.uniform(0.0, 1.5))
    acc, f1, z1 = held_beam(event, n, t_event)
    a_gain = Params().a_gain
    t = np.arange(n) * DT
    if baseline == "steady":
        base = np.full(n, -2.0)
    elif baseline == "offset":
        base = np.full(n, float(rng.uniform(20.0, 130.0)))
    elif baseline == "stab":
        b0, tau = float(rng.uniform(40.0, 130.0)), float(rng.uniform(8.0, 15.0))
        base = b0 * np.exp(-t / tau)
    else:  # a shock at the strike: the baseline jumps and creeps back
        jump, tau = float(rng.choice([-1.0, 1.0]) * rng.uniform(80.0, 150.0)), float(rng.uniform(8.0, 15.0))
        base = np.where(t >= t_event, jump * np.exp(-(t - t_event) / tau), 0.0) - 2.0
    a = np.floor(a_gain * acc + base + rng.normal(0.0, 0.3, n) + 0.5)
    u = np.where(np.arange(n) >= 50, level, 0.0)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{'ping' if event == 'strike' else 'log_dec_hold_and_release'}_{baseline}_{seed}" \
                    f"_SLFR_RTP_OL_Test_uend={level:g}.txt"
    path.write_text(_rig_text(u, u, np.full(n, theta0), a))
    return path, Hidden("held", False, theta0, DT, f1, z1, True, {"event": event, "baseline": baseline,
                                                                    "t_event": t_event})


# --- cut, downsampled and cut-down copies of ordinary runs ---------------------------------

KINDS = {"open_loop_pulses": "open-loop", "p_step": "p", "lead_step": "lead"}
"""The runs :func:`write_cut` cuts (the thesis's), by the blind rig's controller kind."""


def _run(kind: str, seed: int, effects: dict | None = None, n: int = 1000) -> tuple[str, np.ndarray, Run]:
    """A run of the blind rig: one of :data:`KINDS` (the thesis's), 2 s."""
    u = reference(kind, n)
    sim = simulate(KINDS[kind], u, dict(effects or {}), np.random.default_rng([seed, 2610]))
    return kind, u, sim


def _cut_text(text: str, start: int) -> str:
    lines = text.splitlines()
    rig = lines[0].startswith("#")  # the rig's "#" layout (t, n, ...), else the 2014 one (a name line; t, ...)
    head = [x for x in lines if x.startswith("#")] if rig else lines[:1]
    rows = [x.split("\t") for x in lines[len(head):]][start:]
    t0 = float(rows[0][0])
    out = [[_num(float(r[0]) - t0)] + ([str(k)] + r[2:] if rig else r[1:]) for k, r in enumerate(rows)]
    return "\n".join(head + ["\t".join(r) for r in out]) + "\n"


def cut_log(src: Path, dst: Path, start: int) -> Path:
    """A log of the rig's ``#`` layout (columns t, n, ...) or its 2014 layout (a line of names;
    t first) cut from row ``start`` on: t re-zeroed, n renumbered, every other column as
    logged (the lab's ``_trunc`` copies)."""
    Path(dst).write_text(_cut_text(Path(src).read_text(), start))
    return Path(dst)


def write_cut(folder: Path, seed: int, kind: str = "open_loop_pulses", start: int = 80,
              effects: dict | None = None) -> tuple[Path, Hidden]:
    """A run cut from row ``start`` on (t re-zeroed, n renumbered, θ and a as logged), in the
    rig's layout with the run's header (the lab's ``_trunc`` copies).

    Parameters
    ----------
    folder : Path
    seed : int
    kind : {"open_loop_pulses", "p_step", "lead_step"}
    start : int
        The first row kept (open-loop pulses: +100 over rows 20-69; a P step at row 50; the
        lead's step at row 10).
    effects : dict, optional
        Hidden effects of the blind rig (e.g. Coulomb friction).
    """
    kind, u, sim = _run(kind, seed, effects)
    moving = bool(np.any(np.diff(sim.theta_true[max(start - 2, 0):start + 3]) != 0))
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{kind}_{seed}_from_{start}_trunc.txt"
    path.write_text(_cut_text(format_run(kind, sim) if kind != "open_loop_pulses" else
                              _rig_text(sim.u, sim.v, sim.theta, sim.a, head=tuple(header(kind))), start))
    return path, Hidden("cut", moving, float(sim.theta[start]), DT, extra={"start": start, "run": kind})


def write_copy(folder: Path, seed: int, every: int = 2, start: int = 0,
               effects: dict | None = None) -> tuple[Path, Hidden]:
    """The open-loop pulse run as a cut-down copy: columns ``t v theta a`` (no header, no n,
    no u), from row ``start``, every ``every``-th row (the lab's ``_trunc_trunc_downsampled``).
    """
    kind, u, sim = _run("open_loop_pulses", seed, effects)
    rows = np.arange(start, len(sim.u), every)
    lines = ["t\tv\ttheta\ta"] + ["\t".join(_num(float(x)) for x in ((k - start) * DT, sim.v[k], sim.theta[k], sim.a[k]))
                                  for k in rows]
    moving = bool(np.any(np.diff(sim.theta_true[max(start - 2, 0):start + 3]) != 0))
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"pulse_{seed}_copy_every_{every}.txt"
    path.write_text("\n".join(lines) + "\n")
    return path, Hidden("copy", moving, float(sim.theta[start]), DT * every, extra={"start": start})


def write_unzeroed(folder: Path, seed: int, theta0: float = -3.0, effects: dict | None = None) -> tuple[Path, Hidden]:
    """The thesis's P step (kp = 2, 50 counts at row 50) on an encoder that read ``theta0``
    with the hub at rest: the loop's error u - θ ran from there (v[k] = 2 (u - θ[k-1]))."""
    kind, u, sim = _run("p_step", seed, effects)
    # the same loop, its θ offset: re-run with the reference moved by -theta0 and θ read +theta0
    shifted = simulate("p", u - theta0, dict(effects or {}), np.random.default_rng([seed, 2610]))
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"p_step_{seed}_unzeroed_SLFR_RTP_P_control_kp=2.0.txt"
    path.write_text(format_run("p_step", Run(u, shifted.v, shifted.theta + theta0, shifted.a, u,
                                             shifted.applied, shifted.theta_true + theta0, shifted.motor)))
    return path, Hidden("unzeroed", False, theta0, extra={"v0": float(shifted.v[0])})


def write_unplugged(folder: Path, seed: int, creep: float = 40.0) -> tuple[Path, Hidden]:
    """The P step with an a column that is an unplugged input: -66 counts, noise of 3, a creep of
    ``creep`` counts over the run, row 0 a zero (the 2014 layout's first row)."""
    kind, u, sim = _run("p_step", seed, n=3000)
    rng = np.random.default_rng([seed, 2611])
    n = len(u)
    a = np.round(-66.0 + creep * np.arange(n) / n + rng.normal(0.0, 3.0, n))
    a[0] = 0.0
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"p_step_{seed}_unplugged_SLFR_RTP_P_control_kp=2.0.txt"
    path.write_text(format_run("p_step", Run(u, sim.v, sim.theta, a, u, sim.applied, sim.theta_true, sim.motor)))
    return path, Hidden("unplugged", accel_tip=False)


def write_unpowered(folder: Path, seed: int, effects: dict | None = None) -> tuple[Path, Hidden]:
    """The open-loop pulses logged while the amplifier was off: the hub never moves (v logged,
    not applied); the pulses are 0.1 s, too short for a hub-held test."""
    kind, u, sim = _run("open_loop_pulses", seed, {**(effects or {}), "saturation": 1e-9})
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"pulse_{seed}_unpowered_SLFR_RTP_OL_Test_uend=0.txt"
    path.write_text(_rig_text(sim.u, sim.v, sim.theta, sim.a))
    return path, Hidden("unpowered", extra={"applied": float(np.max(np.abs(sim.applied)))})


def first_mode() -> tuple[float, float]:
    """The held beam's first mode of :func:`write_beam_test` (Hz, damping ratio)."""
    p = Params()
    return held_first_mode(p, 4, beta_for_damping(p, 0.005, 4))




def write_kept_ticks(folder: Path, seed: int, kind: str = "p_step", every: int = 2, start: int = 0,
                     kp: float = 2.0, header_kp: float | None = None, alignment: int = 1,
                     effects: dict | None = None, header: str = "true") -> tuple[Path, Hidden, Run]:
    """A closed-loop step of the blind rig (its law at every 0.002 s tick) logged every
    ``every``-th tick from tick ``start``, t and n as the loop counted them (a logger at 250 Hz
    beside a 500 Hz loop), the header's kp ``header_kp`` (a lying header) or the true one;
    ``header`` "none" (the column line only) or "open_loop" (the lab's ``#SLFR RTP OL_Test``).

    Returns
    -------
    (Path, Hidden, Run)
        The log, the truth (``extra``: kp, alignment, every) and the whole run (every tick).
    """
    u = reference(kind, 1000)
    sim = simulate(KINDS[kind], u, dict(effects or {}), np.random.default_rng([seed, 2611]), kp=kp,
                   alignment=alignment)
    lines = format_run(kind, sim).splitlines()
    head = [x for x in lines if x.startswith("#")]
    if kind == "p_step":
        head = [f"#kp={kp if header_kp is None else header_kp!r}" if x.startswith("#kp=") else x for x in head]
    if header != "true":
        head = (["#SLFR RTP OL_Test"] if header == "open_loop" else []) + head[-1:]
    rows = [x for x in lines if not x.startswith("#")][start::every]
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{kind}_{seed}_every_{every}_from_{start}.txt"
    path.write_text("\n".join(head + rows) + "\n")
    return path, Hidden("kept_ticks", False, float(sim.theta[start]), DT,
                        extra={"kp": kp, "alignment": alignment, "every": every}), sim


__all__ = ["Hidden", "cut_log", "first_mode", "held_beam", "write_beam_test", "write_copy", "write_cut",
           "write_kept_ticks", "write_unplugged", "write_unpowered", "write_unzeroed"]
