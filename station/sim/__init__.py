"""The simulated SFLR device (both protocols) on the FEM plant.

- :mod:`station.sim.device`: :class:`~station.sim.device.SimDevice`, the firmware logic (no I/O, no clock).
- :mod:`station.sim.hardware`: DAC clamp, sensor latch, accelerometer offset and zeroing.
- :mod:`station.sim.driver`: pacing (lockstep / realtime) and fault injection for transports.
- :mod:`station.sim.protocol_sim`: the ``sim://`` pyserial URL handler (in process).
- :mod:`station.sim.pty_server`: the device on a pty (out of process, ``station sim-device --pty``).
- :mod:`station.sim.standin`: a plant and sensors that make tick order observable, for tests.
"""
