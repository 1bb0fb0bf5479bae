"""Control station for the single flexible link robot (SFLR).

Runs step tests on the rig or on a simulated rig (a FEM plant model behind a
simulated serial device), logs every run without loss, and replays logged runs.
See README.md and docs/ for the command line and DESIGN.md (shared) for the rig's facts.
"""

import logging

__version__ = "0.1.0"

# a library's loggers stay silent unless the application configures them (the logging HOWTO's
# rule for libraries): never Python's last-resort handler printing a record on stderr
logging.getLogger("station").addHandler(logging.NullHandler())

from station.rig import DT  # noqa: E402,F401  (re-exported for users: the rig's sample time, s)
