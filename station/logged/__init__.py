"""A logged run understood: which controller ran it, its alignment, sample time, whether it
was closed loop or a hub-held beam test, its reference, and the run simulated on a model as
the rig ran it.

- ``run``: :class:`LoggedRun` (``LoggedRun.from_path(path)``, ``LoggedRun(log)``), the
  one place that answers those questions; ``run.simulate(model) -> ModelRun``.
- ``controller``: which controller ran a log (our header's spec; the rig's header, its
  printed coefficients matched to the known designs, a PID header matched to a standard
  discretization; else inferred from the data): :func:`identify_controller`,
  :func:`rig_controller`.
- ``simulate``: :func:`simulate_log`, :class:`ModelRun` (the model glue).
- ``reference``: what a logged u is (:class:`Reference`, :func:`classify_reference`: the one
  definition of a step).
- ``accelerometer``: an a column that reads only noise, and whether the accelerometer's mass
  was on the beam (θ/v's first antiresonance; :attr:`LoggedRun.mounting`,
  :meth:`LoggedRun.model_for`).
- ``device``: the device's command quantization (the sample time is :attr:`station.runlog.RunLog.dt`).

Layering: this package sits above ``station.analysis``, ``station.control``,
``station.plant`` and ``station.runlog`` and imports only those (and
``station.errors``). Replay, compare, survey and the diagnosis sit above it; nothing here
imports them.
"""

from station.logged.controller import (
    PRINTED_TOLERANCE,
    ControllerId,
    identify_controller,
    log_controller,
    rig_controller,
)
from station.logged.device import command_quantization
from station.logged.run import REPRODUCED_TOLERANCE, LoggedRun
from station.logged.simulate import ModelRun, compared_theta, simulate_log

__all__ = [
    "PRINTED_TOLERANCE", "REPRODUCED_TOLERANCE",
    "ControllerId", "LoggedRun", "ModelRun",
    "command_quantization", "compared_theta", "identify_controller", "log_controller", 
    "rig_controller", "simulate_log",
]
