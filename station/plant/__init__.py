"""FEM plant model of the SFLR (thesis ch. III–IV, DESIGN.md "FEM plant"); no I/O.

- `load_params`, `Params` (``parameters``): parameter sets (``params/<name>.toml``), SI units.
- `build_continuous` (``fem``): continuous state space from v (DAC counts) to [theta, a]
  (counts); `beam_frequencies`, `beam_modes`: the beam-only eigen-solver (verification).
- `DiscretePlant`, `Sensors` (``discrete``): the exact-ZOH sampled plant and the rig's
  sensors (their quantization is :func:`station.rounding.sensor_count`).
- `LinearForm`, `linear_form` (``modal``): the modal form of the sampled plant, cached.
- ``kernel``: the compiled sample loop and `ModelPlant` (a Model stepped tick by tick).
- `Model`, `load_model` (``model``): parameter set + element count + effects
  (``effects``), one TOML file; built-ins in ``models/``.
- `simulate`, `SimResult` (``simulate``): a whole closed- or open-loop run (a Model's
  effects included).
- `modal_summary`, `with_beam_damping` (``modes``): natural frequencies, theta/v
  antiresonances, Rayleigh beam damping for a target first-mode damping ratio.
- `closed_loop`, `closed_loop_spectral_radius` (``stability``): small-signal closed-loop poles.

Imports within: parameters <- fem <- modes, discrete <- modal <- kernel <- model <- simulate
(effects uses modes; kernel uses effects' friction levels). From the rest of the station it may import only
:mod:`station.errors`, :mod:`station.rounding` and :mod:`station.control` (the
compensator types and the controller contract, for `simulate`).
"""

from station.plant.discrete import DiscretePlant, Sensors, quantize
from station.plant.fem import beam_frequencies, beam_modes, build_continuous, state_matrices
from station.plant.kernel import ModelPlant
from station.plant.modal import LinearForm, linear_form
from station.plant.model import Model, load_model
from station.plant.modes import ModalSummary, modal_summary, with_beam_damping
from station.plant.parameters import Params, load_params
from station.plant.simulate import SimResult, simulate
from station.plant.stability import closed_loop, closed_loop_spectral_radius

__all__ = [
    "DiscretePlant", "LinearForm", "ModalSummary", "Model", "ModelPlant", "Params", "Sensors", "SimResult",
    "beam_frequencies", "beam_modes", "build_continuous", "closed_loop", "closed_loop_spectral_radius",
    "linear_form", "load_model", "load_params", "modal_summary", "quantize", "simulate", "state_matrices",
    "with_beam_damping",
]
