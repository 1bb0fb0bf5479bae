"""The simulated rig's hardware as the firmware sees it: DAC, encoder, accelerometer.

Both protocols' device logic drive the plant through :class:`Hardware`, so the physics
(clamp at the DAC, latch before the tick's output acts, the accelerometer's offset at
rest, software zeroing) is written once. Source: ``shared/DESIGN.md`` ("The rig",
"Timing and log rows") and ``shared/spec/protocol.md`` (v1 tick order, START).
"""

from __future__ import annotations

from dataclasses import dataclass

from station.rig import DAC_LIMIT

ACCEL_OFFSET = -2.0
"""Accelerometer reading at rest, ADC counts (DESIGN.md: "offset ≈ −2 counts at rest")."""

ZERO_ACCEL_READINGS = 16
"""Readings averaged by START bit1, one per tick (spec: "averages 16 accelerometer readings")."""


@dataclass(frozen=True, slots=True)
class Reading:
    """One latch of the sensors.

    Attributes
    ----------
    theta : int
        Encoder counts since the last zeroing.
    a : int
        Accelerometer, ADC counts, the firmware's offset removed once zeroed.
    """

    theta: int
    a: int


class Hardware:
    """Plant + sensors + the firmware's zero offsets.

    Parameters
    ----------
    plant : object
        ``reset()``, ``outputs() -> (theta, a)`` noise-free floats (encoder counts, ADC
        counts), ``advance(v)`` one zero-order-hold step of ``dt``; e.g.
        ``station.plant.DiscretePlant``. Reset here.
    sensors : object
        ``read(theta, a) -> (int, int)``: quantised, noisy readings; e.g.
        ``station.plant.Sensors``.
    accel_offset : float, default :data:`ACCEL_OFFSET`
        Added to the plant's acceleration before the ADC reads it, counts.
    v_limit : int, default 255
        The DAC's range, ±counts; :meth:`clamp` limits every output to it.

    Attributes
    ----------
    encoder_zero, accel_zero : int
        Subtracted from every reading (the firmware's zeroing: :meth:`zero_encoder`;
        the v1 firmware sets ``accel_zero`` after START bit1's averaging ticks).
    """

    def __init__(self, plant, sensors, accel_offset: float = ACCEL_OFFSET, v_limit: int = int(DAC_LIMIT)) -> None:
        self.plant = plant
        self.sensors = sensors
        self.accel_offset = float(accel_offset)
        self.v_limit = int(v_limit)
        self.encoder_zero = 0
        self.accel_zero = 0
        plant.reset()
        self._noise_state = _rng_state(sensors)

    def restart(self) -> None:
        """A run starts (v1 START, legacy 'q'): the plant at rest and the sensors' noise
        restarted from its seed, so identical runs give identical readings whatever ran
        before. The encoder zero moves with the plant: the real device does not move the hub
        on START, so the encoder reads at rest what it read just before (a legacy client's
        '7' then 'q' sees θ0 = 0 on every run). The firmware's other zero offsets are the
        firmware's (START's flags set them)."""
        before = self.read().theta
        self.plant.reset()
        self.encoder_zero = self.read().theta + self.encoder_zero - before
        if self._noise_state is not None:
            self.sensors.rng.bit_generator.state = self._noise_state

    def clamp(self, v: int) -> tuple[int, bool]:
        """``v`` limited to ±v_limit, and whether it had to be (SATURATED).

        Parameters
        ----------
        v : int
            The chosen output, DAC counts.

        Returns
        -------
        clamped : int
            ``v`` limited to ±v_limit.
        saturated : bool
            Whether it had to be limited.
        """
        c = max(-self.v_limit, min(self.v_limit, int(v)))
        return c, c != v

    def read(self) -> Reading:
        """Latch both sensors at the plant's current state, without advancing it."""
        theta, a = self.plant.outputs()
        raw_theta, raw_a = self.sensors.read(theta, a + self.accel_offset)
        return Reading(raw_theta - self.encoder_zero, raw_a - self.accel_zero)

    def tick(self, v: int) -> Reading:
        """One interrupt tick with output ``v`` (already clamped): latch, then let ``v`` act for one step.

        The readings see the state x_k, before ``v`` has had any effect (DESIGN.md,
        "Timing and log rows"); the plant then advances to x_{k+1}.

        Parameters
        ----------
        v : int
            The output for this tick, DAC counts, already clamped.

        Returns
        -------
        Reading
            The sensors as latched at the start of the tick.
        """
        reading = self.read()
        self.plant.advance(v)
        return reading

    def zero_encoder(self) -> None:
        """Make the current encoder position read 0 (v1 START bit0, legacy '7')."""
        self.encoder_zero += self.read().theta


def _rng_state(sensors):
    """The state of the sensors' numpy Generator (``sensors.rng``), or None when they have none."""
    rng = getattr(sensors, "rng", None)
    bitgen = getattr(rng, "bit_generator", None)
    return None if bitgen is None else bitgen.state
