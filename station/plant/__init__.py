"""FEM plant model of the SFLR (thesis ch. III–IV, DESIGN.md "FEM plant"); no I/O.

- `load_params`, `Params`: parameter sets (``params/<name>.toml``), SI units.
- `build_continuous`: continuous state space from v (DAC counts) to [theta, a] (counts).
- `DiscretePlant`, `Sensors`: the exact-ZOH sampled plant and the rig's sensors.
- `simulate`: a whole closed- or open-loop run, compiled sample loop (a Model's effects
  included).
- `Model`, `load_model` (``station.plant.model``): parameter set + element count +
  effects (``station.plant.effects``), one TOML file; built-ins in ``models/``.
- `beam_frequencies`, `beam_modes`: the beam-only eigen-solver (verification).
- `modal_summary`: natural frequencies and theta/v antiresonances of the SFLR model;
  `with_beam_damping`: Rayleigh beam damping for a target first-mode damping ratio.
- `closed_loop`, `closed_loop_spectral_radius`: small-signal closed-loop poles.
"""

from station.plant.discrete import DiscretePlant, Sensors, quantize
from station.plant.fem import beam_frequencies, beam_modes, build_continuous, state_matrices
from station.plant.modes import ModalSummary, modal_summary, with_beam_damping
from station.plant.parameters import Params, load_params
from station.plant.simulate import simulate
from station.plant.model import Model, load_model
from station.plant.stability import closed_loop, closed_loop_spectral_radius

__all__ = [
    "DiscretePlant", "ModalSummary", "Model", "Params", "Sensors", "beam_frequencies", "beam_modes",
    "build_continuous", "closed_loop", "closed_loop_spectral_radius", "load_model", "load_params",
    "modal_summary", "quantize", "simulate", "state_matrices", "with_beam_damping",
]
