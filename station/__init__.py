"""Control station for the single flexible link robot (SFLR).

Runs step tests on the rig or on a simulated rig (a FEM plant model behind a
simulated serial device), logs every run without loss, and replays logged runs.
See README.md and docs/ for the command line and DESIGN.md (shared) for the rig's facts.
"""

__version__ = "0.1.0"

DT = 0.002
"""Sample time of the rig's interrupt, s (500 Hz)."""
