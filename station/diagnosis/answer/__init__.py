"""The answer: the typed result and its JSON (``result``), filled from a finished search
(``records``), in words (``prose``) and as report.html (``report``; it loads matplotlib, so
nothing imports it at start-up).

May import :mod:`station.diagnosis.honesty` and the rooms below it.
"""
