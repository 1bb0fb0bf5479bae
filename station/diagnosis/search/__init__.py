"""The search and its values: bounded fitting on a piecewise-constant cost (``bounded``),
every candidate alone and the acceptance against luck (``selection``), forward selection with
its lookahead (``stepwise``), the least-squares or likelihood values (``estimator``) and the
set-up a search runs in (``workbench``).

May import :mod:`station.diagnosis.runs` and :mod:`station.diagnosis.units`.
"""
