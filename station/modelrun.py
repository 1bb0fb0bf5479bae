"""Old home of the model glue of a logged run, now :mod:`station.logged` (:meth:`station.logged.LoggedRun.simulate`,
:func:`station.logged.simulate_log`); these names stay importable from here for old callers."""

from station.logged.device import command_quantization
from station.logged.simulate import ModelRun, simulate_log

__all__ = ["ModelRun", "command_quantization", "simulate_log"]
