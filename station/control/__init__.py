"""Discrete compensators (P, lead Gth, accelerometer feedback Ga) and references.

No I/O. See docs/ARCHITECTURE.md "station.control" and DESIGN.md "Compensators".
"""

from station.control.compensator import Compensator, OpenLoop
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
    "ACCEL_DEN_S", "ACCEL_NUM_S", "KINDS", "LEAD_DEN_S", "LEAD_NUM_S",
    "Compensator", "DiscreteTF", "OpenLoop",
    "controller_from_spec", "file_reference", "lead_controller", "load_compensator_file",
    "make_controller", "p_controller", "pulse_reference", "step_reference",
    "swept_sine_reference", "tustin",
]
