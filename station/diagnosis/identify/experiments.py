"""The experiments ``station identify`` can run on a device: a controller, a reference and an
amplitude (:class:`Experiment`), the thesis's four (:data:`THESIS_EXPERIMENTS`) and the small
set a design chooses from (:func:`candidate_experiments`).

References (u[k], encoder counts in closed loop, DAC counts in open loop; zero for the first
:data:`station.rig.DEFAULT_STEP_TICK` ticks, so every run has samples at rest before it moves):

- ``step``: A from ``step_time`` on;
- ``pulses``: the rig's pulse test, +A for 0.1 s from t = 0.04 s and −A for 0.1 s from t = 1.4 s;
- ``ramp``: from 0 to A at the run's end, slowly (friction's breakaway in open loop, stick-slip
  while tracking in closed loop);
- ``triangle``: 0 → A → −A → 0 (friction in both directions);
- ``stairs``: holds at A/3, 2A/3, A, then back down at 2A/3, A/3 and 0, each a sixth of the
  run (open loop: the motor's speed held at several commands tells Coulomb from viscous
  friction, a still motor that starts only on a higher step shows the breakaway, and one that
  keeps sliding on the way down shows a sliding level below it);
- ``reversals``: :data:`REVERSALS` periods of a triangle ±A (slow reversals: the motor stops
  and starts again at each, where breakaway and sliding friction differ);
- ``chirp``: A sin of a frequency swept linearly from :data:`CHIRP_HZ`'s first to its last;
- ``prbs``: ±A, each level held a whole number of :data:`PRBS_HOLD_TICKS` (seeded, repeatable);
- ``multisine``: sines at :data:`MULTISINE_HZ` with Schroeder phases, peak A.

An experiment runs as a normal ``station step`` (:func:`station.experiment.run_step` with the
reference written as a file, ``FILE:u``), so a person can repeat it by hand.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.control import make_controller
from station.rig import CLAMP, DEFAULT_DURATION, DEFAULT_STEP_TICK, DT

PULSE_TICKS = (20, 700, 50)
"""The rig's pulse test: first pulse's tick, the opposite pulse's tick, their width (0.1 s)."""

CHIRP_HZ = (0.5, 15.0)
"""Frequencies a chirp sweeps, Hz: below the first beam mode (2.5 Hz) to near the second (18 Hz)."""

PRBS_HOLD_TICKS = 20
"""Shortest hold of a PRBS level, ticks (25 Hz): its spectrum covers the first mode and the motor."""

MULTISINE_HZ = (0.5, 1.0, 2.0, 2.5, 3.0, 5.0, 8.0, 12.0, 18.0)
"""Frequencies of the multisine, Hz (dense around the first beam mode)."""

REVERSALS = 3
"""Periods of a ``reversals`` reference over the run."""

STAIRS = (1, 2, 3, 2, 1, 0)
"""The levels of a ``stairs`` reference, in thirds of A, each held a sixth of the run."""

REFERENCE_KINDS = ("step", "pulses", "ramp", "triangle", "stairs", "reversals", "chirp", "prbs", "multisine")
"""Every reference an experiment may have."""

CONTROLLERS = ("open-loop", "p", "lead", "lead-accel")
"""Every controller an experiment may have (the rig's own)."""


@dataclass(frozen=True)
class Experiment:
    """One experiment: a controller, a reference and its amplitude.

    Attributes
    ----------
    controller : {"open-loop", "p", "lead", "lead-accel"}
    reference : str
        One of :data:`REFERENCE_KINDS`.
    amplitude : float
        Encoder counts in closed loop, DAC counts in open loop.
    kp : float or None
        P gain (controller "p"), DAC counts per encoder count.
    step_time : float
        When a step starts, s (other references start at :data:`station.rig.DEFAULT_STEP_TICK`).
    duration : float
        Run length, s.
    """

    controller: str
    reference: str
    amplitude: float
    kp: float | None = None
    step_time: float = DEFAULT_STEP_TICK * DT
    duration: float = DEFAULT_DURATION

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise ValueError(f"controller {self.controller!r}: expected one of {', '.join(CONTROLLERS)}")
        if self.reference not in REFERENCE_KINDS:
            raise ValueError(f"reference {self.reference!r}: expected one of {', '.join(REFERENCE_KINDS)}")
        if (self.kp is not None) != (self.controller == "p"):
            raise ValueError("kp is the P controller's gain: given for controller 'p' only, and always for it")

    @property
    def closed(self) -> bool:
        """Closed loop (the reference is in encoder counts)."""
        return self.controller != "open-loop"

    @property
    def label(self) -> str:
        """In words, e.g. "open-loop ramp to 40 DAC counts", "P (kp 2) step of 50 counts"."""
        unit = "counts" if self.closed else "DAC counts"
        who = {"open-loop": "open-loop", "lead": "lead", "lead-accel": "lead + accelerometer"}.get(
            self.controller) or f"P (kp {self.kp:g})"
        a = f"{self.amplitude:g} {unit}"
        what = {"step": f"step of {a}", "pulses": f"±{a} pulses", "ramp": f"ramp to {a}",
                "triangle": f"triangle ±{a}", "stairs": f"stairs up to {a} and down (holds)",
                "reversals": f"{REVERSALS} reversals ±{a}", "chirp": f"chirp {CHIRP_HZ[0]:g}-{CHIRP_HZ[1]:g} Hz of ±{a}",
                "prbs": f"PRBS ±{a}", "multisine": f"multisine of peak {a}"}[self.reference]
        return f"{who} {what}"

    @property
    def slug(self) -> str:
        """A file-name part, e.g. "open-loop-ramp-40", "p2-step-50"."""
        who = f"p{self.kp:g}" if self.controller == "p" else self.controller
        return f"{who}-{self.reference}-{self.amplitude:g}".replace(".", "_")

    def u(self, dt: float = DT) -> np.ndarray:
        """The reference u[k], shape (round(duration/dt),): encoder counts closed loop, DAC counts open loop.

        Parameters
        ----------
        dt : float
            Sample time, s.

        Returns
        -------
        ndarray, shape (round(duration/dt),)
            The reference (:func:`reference`), encoder counts closed loop, DAC counts open loop.

        Raises
        ------
        ValueError
            A run too short for the reference (:func:`reference`).
        """
        n = int(round(self.duration / dt))
        return reference(self.reference, self.amplitude, n, int(round(self.step_time / dt)), dt)

    def controller_object(self, limit: float = CLAMP, dt: float = DT):
        """The controller as the device's run uses it (:func:`station.control.make_controller`).

        Parameters
        ----------
        limit : float
            The clamp, ±DAC counts (the rig's 200).
        dt : float
            Sample time, s.

        Returns
        -------
        Compensator or OpenLoop
            What :func:`station.control.make_controller` makes of :attr:`controller`, with
            :attr:`kp` (2 when None) and the clamp.

        Raises
        ------
        StationError
            A bad kp, limit or dt (:func:`station.control.make_controller`).
        """
        return make_controller(self.controller, dt=dt, kp=2.0 if self.kp is None else self.kp, limit=limit)

    def to_json(self) -> dict:
        """``{"controller", "kp", "reference": {"kind", "amplitude", "step_time_s", "duration_s"}, "label"}``.

        Returns
        -------
        dict
            As above: ``amplitude`` in counts, ``step_time_s`` and ``duration_s`` in s (a reference
            other than a step gives its start, :data:`station.rig.DEFAULT_STEP_TICK` ticks).
        """
        return {"controller": self.controller, "kp": self.kp,
                "reference": {"kind": self.reference, "amplitude": self.amplitude,
                              "step_time_s": self.step_time if self.reference == "step" else DEFAULT_STEP_TICK * DT,
                              "duration_s": self.duration},
                "label": self.label}


def reference(kind: str, amplitude: float, n: int, step_tick: int = DEFAULT_STEP_TICK, dt: float = DT) -> np.ndarray:
    """u[k] of a reference kind (module docstring), shape (n,).

    Parameters
    ----------
    kind : str
        One of :data:`REFERENCE_KINDS`.
    amplitude : float
        Peak, counts.
    n : int
        Ticks.
    step_tick : int
        First tick of a step.
    dt : float
        Sample time, s.

    Returns
    -------
    ndarray, shape (n,)
        u[k], in ``amplitude``'s counts: 0 before the reference starts, peak |u| ≤ |amplitude|.

    Raises
    ------
    ValueError
        Unknown kind, or a run too short for it.
    """
    u = np.zeros(n)
    k0 = DEFAULT_STEP_TICK
    m = n - k0  # ticks that move
    if m < 2:
        raise ValueError(f"{n} ticks: too short a run for a {kind} reference")
    t = np.arange(m) * dt
    if kind == "step":
        u[step_tick:] = amplitude
    elif kind == "pulses":
        first, back, width = PULSE_TICKS
        u[first:first + width] = amplitude
        u[back:back + width] = -amplitude
    elif kind == "ramp":
        u[k0:] = amplitude * np.arange(m) / (m - 1)
    elif kind == "triangle":
        phase = np.arange(m) / m  # one period over the run: 0 -> A -> -A -> 0
        u[k0:] = amplitude * np.where(phase < 0.25, 4 * phase, np.where(phase < 0.75, 2 - 4 * phase, 4 * phase - 4))
    elif kind == "stairs":
        hold = -(-m // len(STAIRS))
        u[k0:] = amplitude / 3.0 * np.repeat(np.asarray(STAIRS, float), hold)[:m]
    elif kind == "reversals":
        phase = (np.arange(m) * REVERSALS / m) % 1.0
        u[k0:] = amplitude * np.where(phase < 0.25, 4 * phase, np.where(phase < 0.75, 2 - 4 * phase, 4 * phase - 4))
    elif kind == "chirp":
        f0, f1 = CHIRP_HZ
        span = m * dt
        u[k0:] = amplitude * np.sin(2 * np.pi * (f0 * t + (f1 - f0) * t ** 2 / (2 * span)))
    elif kind == "prbs":
        levels = np.random.default_rng(1).choice([-1.0, 1.0], size=-(-m // PRBS_HOLD_TICKS))
        u[k0:] = amplitude * np.repeat(levels, PRBS_HOLD_TICKS)[:m]
    elif kind == "multisine":
        k = np.arange(1, len(MULTISINE_HZ) + 1)
        phases = -np.pi * k * (k - 1) / len(MULTISINE_HZ)  # Schroeder: a low crest factor
        x = sum(np.sin(2 * np.pi * f * t + p) for f, p in zip(MULTISINE_HZ, phases))
        u[k0:] = amplitude * x / np.max(np.abs(x))
    else:
        raise ValueError(f"reference {kind!r}: expected one of {', '.join(REFERENCE_KINDS)}")
    return u + 0.0  # no -0.0


THESIS_EXPERIMENTS = (
    Experiment("p", "step", 50.0, kp=2.0, step_time=0.1),
    Experiment("lead", "step", 100.0),
    Experiment("lead-accel", "step", 200.0),
    Experiment("open-loop", "pulses", 100.0),
)
"""The thesis's four (DESIGN.md, tests/blind/generator.py): P kp = 2 step of 50 at 0.1 s, lead
step of 100, lead + accelerometer step of 200 (both at 0.02 s), open-loop ±100 pulses."""


def candidate_experiments() -> list[Experiment]:
    """The experiments a design chooses from: each reference at a few amplitudes under each
    controller where it makes sense (open-loop ramps at three speeds, triangles, stairs of
    holds, slow reversals and small pulses for friction; closed-loop steps, chirps, PRBS and
    multisines for the dynamics). About 40, all 2 s.

    Returns
    -------
    list of Experiment
        The candidates, open-loop ones first, then per controller (P, lead, lead-accel).
    """
    ol = [("ramp", (20, 40, 80)), ("triangle", (30, 60)), ("stairs", (20, 40)), ("reversals", (20, 40)),
          ("pulses", (30, 60, 150, 200)), ("prbs", (30, 60)), ("chirp", (30, 60)), ("multisine", (40, 80))]
    closed = {"p": [("step", (10, 25, 100, 200)), ("ramp", (100, 300)), ("chirp", (20, 50)), ("prbs", (20, 50))],
              "lead": [("step", (25, 200, 400)), ("chirp", (20, 50)), ("prbs", (50,)), ("multisine", (50,))],
              "lead-accel": [("step", (50, 400)), ("chirp", (50,)), ("prbs", (50,))]}
    out = [Experiment("open-loop", kind, float(a)) for kind, amps in ol for a in amps]
    for ctrl, refs in closed.items():
        out += [Experiment(ctrl, kind, float(a), kp=2.0 if ctrl == "p" else None) for kind, amps in refs for a in amps]
    return out


def write_reference(experiment: Experiment, path: str | Path, dt: float = DT) -> Path:
    """Write an experiment's reference as a two-column log (``t``, ``u``) that ``station step
    --reference FILE:u`` reads (:func:`station.control.file_reference`).

    Parameters
    ----------
    experiment : Experiment
    path : str or Path
        The file (its folder must exist).
    dt : float
        Sample time, s.

    Returns
    -------
    Path
        ``path``: tab-separated, a ``t u`` header and one row per tick (t in s, u in counts).

    Raises
    ------
    ValueError
        A run too short for the reference (:func:`reference`).
    OSError
        The file cannot be written (its folder missing, no permission).
    """
    u = experiment.u(dt)
    path = Path(path)
    rows = "\n".join(f"{k * dt:.6f}\t{x:.10g}" for k, x in enumerate(u))
    path.write_text("t\tu\n" + rows + "\n")
    return path
