"""Compensator design on a model (``station tune``, DESIGN.md "Designing a compensator on a model").

- `space`: the rig's structures (p, lead, lead-accel), a filter at the second beam mode (notch,
  roll-off, damper) and the reference shaper as searched parameters.
- `tip`: the beam's tip in a simulated run: its position and its residual vibration.
- `evaluate`: one design on one model: the step as ``station step`` runs it, figures (the hub's
  and the tip's), cost.
- `front`: the trade-off between the hub and the tip, the designs no other beats on both.
- `linear`: the loop's linear part: margins and closed-loop poles.
- `robust`: the set of models a design is judged on (model files, diagnosis JSONs, drawn doubt).
- `search`: bracket (Sobol) and refine (Nelder-Mead, active set) the worst case.
- `executor`: where evaluations run (this process, a process pool, a Dask cluster).
- `tuning`: the design (:func:`tune`); `result`: what it hands back (:class:`TuneResult`, the
  trade-off, the JSON); `verify`: a real ``station step`` on the simulated rig; `figures`,
  `report`: the report.

Imports the control, plant and analysis packages and :mod:`station.experiment` (verify); nothing
imports it but the ``tune`` command and scripts.
"""

import importlib

_WHERE = {"Figures": "evaluate", "Requirements": "evaluate", "RobustSet": "robust", "robust_set": "robust",
          "Budget": "search", "SHAPERS": "space", "STRUCTURES": "space", "DesignSpace": "space",
          "TuneResult": "result", "tune": "tuning", "Verification": "verify", "verify": "verify"}

__all__ = sorted(_WHERE)


def __getattr__(name: str):
    # imported on first use (PEP 562): the tune command's parser, built with every command's
    # at start-up, needs only the light `space` and `robust`, not scipy.signal and control
    if name in _WHERE:
        return getattr(importlib.import_module(f"station.design.{_WHERE[name]}"), name)
    raise AttributeError(f"module 'station.design' has no attribute {name!r}")
