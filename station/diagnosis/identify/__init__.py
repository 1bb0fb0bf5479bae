"""Identifying a rig on the device (``station identify``): what can be run (``experiments``),
the experiment that separates the rivals most (``design``), the loop (``loop``:
``from station.diagnosis.identify.loop import identify``) and report.html (``report``).

May import the pipeline (:func:`station.diagnosis.diagnose`), every room below it and
:mod:`station.experiment` (a run on a device). Not imported by :mod:`station.diagnosis`.
"""
