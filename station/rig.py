"""The rig's facts and the station's defaults: one definition of each (DESIGN.md "The rig").

Every module and script takes these from here; the literals (the sample time, 500 as a
rate, the clamp, the step's tick) appear nowhere else in code (tests/test_rig_facts.py
walks station/ and scripts/ and fails on a literal or a second definition).
``station.DT`` is :data:`DT`, kept for users. Imports the standard library only.

- The rig (DESIGN.md "The rig"): :data:`RATE_HZ`, :data:`DT`, :data:`COUNTS_PER_REV`,
  :data:`COUNTS_PER_RAD`, :data:`DAC_LIMIT`, :data:`CLAMP`.
- The station's defaults for a step test (DESIGN.md "Station defaults"):
  :data:`DEFAULT_AMPLITUDE`, :data:`DEFAULT_STEP_TICK`, :data:`DEFAULT_DURATION`,
  :data:`DEFAULT_SOFT_LIMIT`, :data:`DEFAULT_TIMEOUT`; the thesis's step tests
  :data:`THESIS_STEPS`.
- Settling bands: the thesis's (:data:`THESIS_BAND`, at least :data:`THESIS_BAND_FLOOR`;
  DESIGN.md "Step metrics") and python-control's ``step_info`` (:data:`STEP_INFO_BAND`).
- The tip's residual window (:data:`RESIDUAL_AFTER_S`; DESIGN.md "Designing a compensator
  on a model").
- Sample budgets of the diagnosis: :data:`DIAGNOSE_MAX_SAMPLES` (``station diagnose``
  refuses more) and :data:`SESSIONS_MAX_SAMPLES` (``station survey --diagnose`` cuts to
  it): two budgets, two meanings.
"""

from __future__ import annotations

import math
from types import MappingProxyType

# The rig (DESIGN.md "The rig").

RATE_HZ = 500
"""Rate of the rig's interrupt, Hz: one sample and one command per tick."""

DT = 1.0 / RATE_HZ
"""Sample time of the rig's interrupt, s (0.002 s)."""

COUNTS_PER_REV = 1024
"""Encoder counts per revolution of the base."""

COUNTS_PER_RAD = COUNTS_PER_REV / (2.0 * math.pi)
"""The encoder's gain H = 1024/(2π) counts/rad."""

DAC_LIMIT = 255.0
"""Full scale of the motor command, ±DAC counts (±2.5 V into the power amplifier): no clamp
goes beyond it."""

CLAMP = 200.0
"""The rig software's clamp of the motor command, ±DAC counts ("slightly nonlinear above
±200"): the station's default ``--limit`` and the clamp assumed for the rig's logs."""

MAX_ENCODER_STEP = 40.0
"""Largest plausible encoder change per tick, counts: the rig's top motor speed (act_K·|2πj +
act_p|/act_p ≈ 0.067 rad/s per DAC count, at 255 counts ≈ 5.6 counts per tick) with a margin of
7 for the beam's swing of the hub. A live sample past it ends a run (``--max-step``); a logged
θ past it from both neighbouring rows is a corrupted field (:mod:`station.logged.spikes`)."""

# The station's defaults for a step test (DESIGN.md "Station defaults").

DEFAULT_AMPLITUDE = 100.0
"""Step height, encoder counts."""

DEFAULT_STEP_TICK = 10
"""The tick the step (and any generated reference) starts at: t = 0.02 s."""

DEFAULT_DURATION = 2.0
"""Run length, s."""

DEFAULT_SOFT_LIMIT = 2048.0
"""Encoder soft limit, ±encoder counts (two revolutions): a run stops safely beyond it."""

DEFAULT_TIMEOUT = 0.1
"""Sample timeout, s: the link stops when no valid sample arrives within it."""

THESIS_STEPS = MappingProxyType({"p": 50.0, "lead": 100.0, "lead-accel": 200.0})
"""The thesis's step tests, controller -> step height in encoder counts (P kp = 2, step 50;
lead, step 100; lead + accelerometer, step 200; DESIGN.md "Step metrics")."""

# Settling bands, fractions of the step (DESIGN.md "Step metrics").

THESIS_BAND = 0.01
"""The thesis's settling band: half-width 1 % of the step, at least :data:`THESIS_BAND_FLOOR`."""

THESIS_BAND_FLOOR = 1.0
"""Least half-width of the thesis's settling band, encoder counts (one quantization step)."""

STEP_INFO_BAND = 0.02
"""The 2 % settling band (python-control's ``step_info``; ``station tune``'s figures)."""

# The tip (DESIGN.md "Designing a compensator on a model").

RESIDUAL_AFTER_S = 0.6
"""The tip's residual window starts this long after the step, s, and runs to the run's end."""

# Sample budgets of the diagnosis.

DIAGNOSE_MAX_SAMPLES = 100_000
"""``station diagnose --max-samples``' default: the most samples of all runs together it
takes (200 s of the rig's data); more is refused before any work, naming the longest run
(its cost: docs/benchmarks.md, "The diagnosis")."""

SESSIONS_MAX_SAMPLES = 20_000
"""``station survey --diagnose --max-samples``' default: the samples of all runs together the
sessions' diagnosis uses (40 s of the rig's data); beyond it the longest runs are cut to
their first samples, each cut said (the rig's folder, ten usable runs and 66 000 samples,
then uses the first 3000 samples of its five long runs)."""
