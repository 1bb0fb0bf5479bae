"""A tiny stand-in plant and sensors with the interfaces of :mod:`station.plant`.

Used by the simulated device's tests, where the tick order must be observable exactly:
the plant's state after tick k is known in closed form, so a test can tell which command
acted during which tick. Not a model of the rig.
"""

from __future__ import annotations

import numpy as np

from station.rounding import sensor_count


class StepRecorderPlant:
    """A plant whose outputs reveal the commands that acted on it.

    State after ``k`` steps: theta = v[0] + ... + v[k-1] (encoder counts), a = v[k-1]
    (the last input, ADC counts; 0 before any step). Same interface as
    ``station.plant.DiscretePlant``: :meth:`reset`, :meth:`outputs`, :meth:`advance`.
    """

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Back to rest: theta = 0, a = 0, no steps taken."""
        self.theta = 0.0
        self.a = 0.0
        self.steps = 0

    def outputs(self) -> tuple[float, float]:
        """(theta, a) at the current state, noise-free floats."""
        return self.theta, self.a

    def advance(self, v: float) -> None:
        """One step with input ``v`` held (DAC counts).

        Parameters
        ----------
        v : float
            The input, DAC counts.
        """
        self.theta += v
        self.a = float(v)
        self.steps += 1


class RoundingSensors:
    """Sensors like ``station.plant.Sensors``: theta rounded, a + seeded Gaussian noise rounded
    (:func:`station.rounding.sensor_count`, halves away from zero).

    Parameters
    ----------
    seed : int, default 0
        Seed of the noise generator (a private ``numpy.random.Generator``).
    accel_noise_std : float, default 0.0
        Standard deviation of the accelerometer noise, ADC counts.
    """

    def __init__(self, seed: int = 0, accel_noise_std: float = 0.0) -> None:
        self._rng = np.random.default_rng(seed)
        self.accel_noise_std = accel_noise_std

    def read(self, theta: float, a: float) -> tuple[int, int]:
        """Quantised readings (encoder counts, ADC counts) of the noise-free outputs.

        Parameters
        ----------
        theta, a : float
            Noise-free outputs, encoder counts and ADC counts.
        """
        noise = self._rng.normal(0.0, self.accel_noise_std) if self.accel_noise_std else 0.0
        return int(sensor_count(theta)), int(sensor_count(a + noise))  # the rig's sensors' rule

