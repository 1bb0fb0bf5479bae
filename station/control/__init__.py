"""Discrete compensators (P, lead Gth, accelerometer feedback Ga) and references.

- `contract`: the controller contract (`Controller`), the one command guard
  (`guard_command`, `ControllerFault`) and the clamp before the wire (`wire_limit`).
- `tf`, `compensator`, `designs`: filters, the rig's compensator structure, its designs
  and compensator files; `reference`: u[k] arrays.

No I/O (a file reference reads a run log through :mod:`station.runlog`). Imports
:mod:`station.errors`, :mod:`station.rig`, :mod:`station.rounding` and :mod:`station.runlog` only. See docs/ARCHITECTURE.md
"station.control" and DESIGN.md "Compensators".
"""

from station.control.compensator import Compensator, OpenLoop
from station.control.contract import DAC_LIMIT, Controller, ControllerFault, guard_command, wire_limit
from station.control.designs import (
    ACCEL_DEN_S,
    ACCEL_NUM_S,
    KINDS,
    LEAD_DEN_S,
    LEAD_NUM_S,
    controller_from_spec,
    lead_controller,
    load_compensator_file,
    make_controller,
    p_controller,
)
from station.control.reference import file_reference, pulse_reference, step_reference, swept_sine_reference
from station.control.tf import DiscreteTF, tustin

__all__ = [
    "ACCEL_DEN_S", "ACCEL_NUM_S", "DAC_LIMIT", "KINDS", "LEAD_DEN_S", "LEAD_NUM_S",
    "Compensator", "Controller", "ControllerFault", "DiscreteTF", "OpenLoop",
    "controller_from_spec", "file_reference", "guard_command", "lead_controller", "load_compensator_file",
    "make_controller", "p_controller", "pulse_reference", "step_reference",
    "swept_sine_reference", "tustin", "wire_limit",
]
