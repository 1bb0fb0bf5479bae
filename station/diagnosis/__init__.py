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
   refinement: :mod:`station.diagnosis.search.bounded`) and judged on runs it was not fitted to:
   the ``validate`` runs, or leave-one-run-out over the runs.
4. Acceptance (forward selection, at most three effects, joint refit of all accepted
   effects at each step): the pooled validation cost must fall by at least
   :data:`MIN_RELATIVE_GAIN` (parsimony: an effect must pay for itself) and by at least
   :data:`MIN_NOISE_GAIN` noise variances per sample, both measured from the lower of the
   current model's cost and the cost that tiny perturbations of it reach by luck
   (:data:`NULL_PERTURBATIONS`: quantization and noise alone); otherwise the answer is
   "none".
5. The reported values are refitted on all fit runs.
6. Doubt (:mod:`~station.diagnosis.honesty.doubt`): each accepted value's 95 % interval (profile
   likelihood with the residuals' effective sample size, widened to the range of the
   leave-one-run-out refits and the fit's resolution) and the alternatives: other
   explanations whose validation cost is within what luck and the data's information reach.
7. What stays unexplained (:mod:`~station.diagnosis.honesty.unexplained`): the extended model's θ
   and a residuals against the same statistics of the model simulated again with the
   sensor model's noise and quantization; when structure remains, what it follows.

Before any work, a run given twice (same data rows, as a copy or as a RUN and a
``--validate`` run) is refused, and hub-held beam tests are set aside with a note
(:mod:`~station.diagnosis.runs.admission`).

Rooms, from the bottom up (a room imports only from the rooms below it; the order is the
table in docs/ARCHITECTURE.md "station.diagnosis", checked by tests/test_layers.py):

- ``units``: an effect's value with its unit (:func:`~station.diagnosis.units.format_quantity`);
- ``runs``: a measured run read and simulated as the rig ran it (:class:`RunCase`,
  :func:`load_case`, :func:`simulate_case`), runs given twice refused and hub-held beam tests
  set aside (``admission``), the noise-normalised cost (:class:`Evaluator`), the folds (:class:`Fold`);
- ``search``: bounded fitting (``bounded``), every candidate alone and the acceptance against
  what noise reaches by luck (``selection``), forward selection with a lookahead
  (``stepwise``), least-squares or likelihood values (``estimator``), the set-up a search runs in
  (``workbench``);
- ``honesty``: intervals (:class:`Interval`) and alternatives (:class:`Alternative`)
  (``doubt``), the residuals against the sensor model's null (:class:`Unexplained`), the
  explanations a diagnosis leaves open (``rivals``);
- ``answer``: the typed result (:class:`EffectResult`, :class:`RunReport`, :class:`Diagnosis`
  and its JSON), filled by ``records``; the words (``prose``); ``report``: ``report.html`` with
  its figures (:mod:`station.plots`), not imported here (it loads matplotlib):
  ``from station.diagnosis.answer.report import write_report``;
- ``pipeline``: :func:`diagnose`, the steps in order; ``sessions``: sessions and drift
  (``station survey --diagnose``);
- ``identify``: identifying a rig on the device (``station identify``; not imported here:
  the loop runs experiments through :mod:`station.experiment`): what can be run
  (``experiments``), the candidate that separates the rivals most (``design``), the loop
  (``from station.diagnosis.identify.loop import identify``) and its ``report``.

May import: :mod:`station.analysis` (fits, residual tests, metrics), :mod:`station.plant`,
:mod:`station.control`, :mod:`station.runlog`,
:mod:`station.plots` and :mod:`station.logged` (a logged run understood and simulated on a
model as the rig ran it); ``identify`` also :mod:`station.experiment` (a run on a device).
Never :mod:`station.replay` or :mod:`station.commands`; and nothing
below (analysis, plant, ...) imports the diagnosis.
"""

from station.diagnosis.runs.cases import RunCase, Simulator, load_case, simulate_case
from station.diagnosis.runs.cost import Evaluator
from station.diagnosis.honesty.doubt import Alternative, Interval
from station.diagnosis.runs.folds import Fold
from station.diagnosis.pipeline import diagnose
from station.diagnosis.answer.prose import SIGNATURE_WORDS, summary_paragraph
from station.diagnosis.answer.result import Diagnosis, EffectResult, RunReport
from station.diagnosis.search.selection import (
    MAX_EFFECTS,
    MIN_NOISE_GAIN,
    MIN_RELATIVE_GAIN,
    NULL_PERTURBATIONS,
    SECOND_STEP_CANDIDATES,
)
from station.diagnosis.honesty.unexplained import Unexplained, check_unexplained

__all__ = [
    "Alternative", "Diagnosis", "EffectResult", "Evaluator", "Fold", "Interval", "MAX_EFFECTS", "MIN_NOISE_GAIN",
    "MIN_RELATIVE_GAIN", "NULL_PERTURBATIONS", "RunCase", "RunReport", "SECOND_STEP_CANDIDATES", "SIGNATURE_WORDS",
    "Simulator", "Unexplained", "check_unexplained", "diagnose", "load_case", "simulate_case", "summary_paragraph",
]
