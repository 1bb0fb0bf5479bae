"""Model diagnosis: what the model gets wrong on measured runs, which effect causes it, the
extended model, and the gain on runs it was not fitted to (DESIGN.md "Model diagnosis
contract", issue 8). The entry is :func:`diagnose`; ``station diagnose`` is its CLI.

Method (the vocabulary of MATLAB's System Identification Toolbox: ``compare``, ``resid``,
grey-box estimation with physical parameters and bounds, honest validation data):

1. Every run is simulated as the rig ran it (:meth:`station.logged.LoggedRun.simulate`: the
   log's controller, reference, clamp, detected alignment and command quantization; the
   logged v in open loop).
2. The cost of a model on a set of runs judges θ and a together, each error normalised by
   its own noise level: J = Σ_runs (‖e_θ‖²/σ_θ² + ‖e_a‖²/σ_a²) / Σ 2N, with σ_θ the
   encoder's quantization (1/√12 counts) or more and σ_a ≥ 0.3 counts, both estimated from
   the high-frequency part of the nominal model's residual
   (:func:`station.analysis.residuals.noise_std`). A perfect model has J ≈ 1.
3. Each candidate effect is fitted on the fit runs (grid bracketing, then local
   refinement: :mod:`station.analysis.fitting`) and judged on runs it was not fitted to:
   the ``validate`` runs, or leave-one-run-out over the runs.
4. Acceptance (forward selection, at most three effects, joint refit of all accepted
   effects at each step): the pooled validation cost must fall by at least
   :data:`MIN_RELATIVE_GAIN` (parsimony: an effect must pay for itself) and by at least
   :data:`MIN_NOISE_GAIN` noise variances per sample, both measured from the lower of the
   current model's cost and the cost that tiny perturbations of it reach by luck
   (:data:`NULL_PERTURBATIONS`: quantization and noise alone); otherwise the answer is
   "none".
5. The reported values are refitted on all fit runs.
6. Doubt (:mod:`~station.diagnosis.doubt`): each accepted value's 95 % interval (profile
   likelihood with the residuals' effective sample size, widened to the range of the
   leave-one-run-out refits and the fit's resolution) and the alternatives: other
   explanations whose validation cost is within what luck and the data's information reach.
7. What stays unexplained (:mod:`~station.diagnosis.unexplained`): the extended model's θ
   and a residuals against the same statistics of the model simulated again with the
   sensor model's noise and quantization; when structure remains, what it follows.

Before any work, a run given twice (same data rows, as a copy or as a RUN and a
``--validate`` run) is refused, and hub-held beam tests are set aside with a note
(:mod:`~station.diagnosis.inputs`).

Modules, in the order a diagnosis uses them:

- ``cases``: a measured run read and understood (:class:`RunCase`, :func:`load_case`) and
  simulated as the rig ran it (:func:`simulate_case`);
- ``inputs``: runs judged on themselves refused, hub-held beam tests set aside;
- ``cost``: the noise-normalised cost, cached per effect set (:class:`Evaluator`), the
  noise levels, pooled fits and gains;
- ``folds``: leave-one-run-out or the ``--validate`` runs (:class:`Fold`);
- ``selection``: every candidate alone, screening, joint refits and the acceptance against
  what noise reaches by luck; ``stepwise``: forward selection with a lookahead over its
  first effect;
- ``doubt``: intervals (:class:`Interval`) and alternatives (:class:`Alternative`);
- ``unexplained``: the residuals against the sensor model's null (:class:`Unexplained`);
- ``result``: the typed result (:class:`EffectResult`, :class:`RunReport`,
  :class:`Diagnosis` and its JSON); ``records`` fills it from a finished search;
- ``prose``: the evidence sentences and the summary paragraph;
- ``pipeline``: :func:`diagnose`, the steps in order;
- ``report``: ``report.html`` with its figures (:mod:`station.plots`); not imported here
  (it loads matplotlib): ``from station.diagnosis.report import write_report``.

Identifying a rig on the device (``station identify``; not imported here: the loop runs
experiments through :mod:`station.experiment`): ``experiments`` (what can be run:
:class:`~station.diagnosis.experiments.Experiment`, the thesis's four, the candidates),
``rivals`` (the explanations a diagnosis leaves open), ``experiment_design`` (the candidate
that separates them most), ``identify`` (the loop: ``from station.diagnosis.identify import
identify``) and ``identify_report``.

May import: :mod:`station.analysis` (fits, residual tests, metrics), :mod:`station.plant`,
:mod:`station.control`, :mod:`station.runlog`,
:mod:`station.plots` and :mod:`station.logged` (a logged run understood and simulated on a
model as the rig ran it); ``identify`` also :mod:`station.experiment` (a run on a device).
Never :mod:`station.replay` or :mod:`station.commands`; and nothing
below (analysis, plant, ...) imports the diagnosis.
"""

from station.diagnosis.cases import RunCase, Simulator, load_case, simulate_case
from station.diagnosis.cost import Evaluator
from station.diagnosis.doubt import Alternative, Interval
from station.diagnosis.folds import Fold
from station.diagnosis.pipeline import diagnose
from station.diagnosis.prose import SIGNATURE_WORDS, summary_paragraph
from station.diagnosis.result import Diagnosis, EffectResult, RunReport
from station.diagnosis.selection import (
    MAX_EFFECTS,
    MIN_NOISE_GAIN,
    MIN_RELATIVE_GAIN,
    NULL_PERTURBATIONS,
    SECOND_STEP_CANDIDATES,
)
from station.diagnosis.unexplained import Unexplained, check_unexplained

__all__ = [
    "Alternative", "Diagnosis", "EffectResult", "Evaluator", "Fold", "Interval", "MAX_EFFECTS", "MIN_NOISE_GAIN",
    "MIN_RELATIVE_GAIN", "NULL_PERTURBATIONS", "RunCase", "RunReport", "SECOND_STEP_CANDIDATES", "SIGNATURE_WORDS",
    "Simulator", "Unexplained", "check_unexplained", "diagnose", "load_case", "simulate_case", "summary_paragraph",
]
