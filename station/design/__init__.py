"""Compensator design on a model (``station tune``, DESIGN.md "Designing a compensator on a model").

- `space`: the rig's structures (p, lead, lead-accel) and the reference shaper as searched parameters.
- `evaluate`: one design on one model: the step as ``station step`` runs it, figures, cost.
- `linear`: the loop's linear part: margins and closed-loop poles.
- `robust`: the set of models a design is judged on (model files, diagnosis JSONs, drawn doubt).
- `search`: bracket (Sobol) and refine (Nelder-Mead, active set) the worst case.
- `executor`: where evaluations run (this process, a process pool, a Dask cluster).
- `tuning`: the design (:func:`tune`, :class:`TuneResult`); `verify`: a real ``station step`` on
  the simulated rig; `figures`, `report`: the report.

Imports the control, plant and analysis packages and :mod:`station.experiment` (verify); nothing
imports it but the ``tune`` command and scripts.
"""

from station.design.evaluate import Figures, Requirements
from station.design.robust import RobustSet, robust_set
from station.design.search import Budget
from station.design.space import SHAPERS, STRUCTURES, DesignSpace
from station.design.tuning import TuneResult, tune
from station.design.verify import Verification, verify

__all__ = ["SHAPERS", "STRUCTURES", "Budget", "DesignSpace", "Figures", "Requirements", "RobustSet",
           "TuneResult", "Verification", "robust_set", "tune", "verify"]
