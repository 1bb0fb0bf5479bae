"""Blind test generator: rig-format logs with a hidden effect, from an independent model.

Written from ../shared/DESIGN.md alone, importing nothing from ``station.plant`` or
``station.control`` (numpy/scipy/numba only), so that tests of the model diagnosis never see
logs made by the model they fit. ``fem`` assembles the plant, ``rig`` runs the rig's timing,
compensators, amplifier (truncation, offset, saturation, dead-zone, delay) and sensors,
``substep`` integrates dry friction (Coulomb, static with a Stribeck curve), backlash and
cogging on a sub-step grid, ``generator`` writes the rig's log files
(:func:`generator.write_case`), ``cases`` draws the hidden effects of the blind cases,
including effects in no vocabulary (``rig.OOV``).
"""
