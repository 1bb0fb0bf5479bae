"""Device link: open a device by URL and run one protocol session on it.

Any pyserial URL works: a port path (``/dev/ttyACM0``, a pty), ``socket://host:port``,
``loop://`` and our ``sim://`` (the simulated rig, :mod:`station.sim.protocol_sim`).
A session is the protocol's life cycle: identify the device, start a run, samples in,
commands out, stop. Every read has a timeout; a missing or busy port, or a device that
does not answer, is a :class:`~station.errors.StationError` with a one-line message
naming the port.

Fail-safe (the link's half of it; :mod:`station.loop` has the rest): one wall-clock
deadline per expected sample (pyserial's ``Timeout``), whatever arrives in between;
modular v1 sequence arithmetic (duplicates, stale, dropped) with a miss budget per 100
ticks; a plausibility bound on the encoder change per tick; the catch-up (samples
waiting are handed over in turn, all but the newest skipped) and the lag (how far the
station fell behind, and the held ticks per 100), with samples that come in bursts named
with their latency timer; the device's tick rate. Each ends the run by raising a
:class:`LinkFault` whose ``reason`` is the outcome reason (DESIGN.md "Run outcome").

Both sessions give the loop the same :class:`Sample` ``(n, theta, accel, v_applied,
status)``: n is the tick number from 0 (v1 sequence numbers unwrapped), theta encoder
counts, accel ADC counts, v_applied DAC counts (None for the legacy device, which does
not report it), status the v1 status bits (0 for legacy).

What lives here:

- :mod:`~station.link.port`: :func:`open_port` (asks the OS for low-latency mode on a
  serial device), :func:`sim_url` (pyserial; registers the ``sim://`` handler package by
  name), :class:`PortInfo` / :func:`port_info` / :func:`latency_timer` (the adapter and
  its latency timer).
- :mod:`~station.link.bursts`: :class:`BurstMeter`, :class:`Burst`, :func:`burst_line`
  (samples in bursts, and the line that names the fix).
- :mod:`~station.link.faults`: :class:`LinkLimits` and the :class:`LinkFault` family,
  :class:`DeviceStopped`.
- :mod:`~station.link.session`: :class:`Session`, the fail-safe supervisor (deadline,
  sequence misses, plausibility, rate, lag, counters, every port read and write) and
  :class:`Sample`.
- :mod:`~station.link.v1`, :mod:`~station.link.legacy`: one session class per protocol.
- here: :func:`open_session`, and every public name above (``from station.link import ...``).

Imports: pyserial, :mod:`station.rig` (DT, the sample timeout), :mod:`station.errors` and :mod:`station.protocol`
only; never the loop, the simulator (``sim://`` is found by pyserial, by name) or anything
above them.
"""

from __future__ import annotations

from station.errors import StationError
from station.link.faults import (MISS_WINDOW, POLL_S, RATE_FAST, RATE_SLOW, RATE_WINDOW_S, DeviceStopped,
                                 Interrupted, LagError, LinkFault, LinkLimits, LinkTimeout, RateError, SequenceError)
from station.link.legacy import LegacySession
from station.link.bursts import Burst, BurstMeter, burst_line
from station.link.port import DEFAULT_BAUD, SIM_HANDLERS, PortInfo, latency_timer, open_port, port_info, sim_url
from station.link.session import HANDSHAKE_TIMEOUT, ZERO_ACCEL_TICKS, Sample, Session, logger
from station.link.v1 import FIRST_SEQ_WINDOW, V1Session
from station.rig import DEFAULT_TIMEOUT

__all__ = ["DEFAULT_BAUD", "FIRST_SEQ_WINDOW", "HANDSHAKE_TIMEOUT", "MISS_WINDOW", "POLL_S", "RATE_FAST", "RATE_SLOW",
           "RATE_WINDOW_S", "SIM_HANDLERS", "ZERO_ACCEL_TICKS", "Burst", "BurstMeter", "DeviceStopped", "Interrupted",
           "LagError", "LegacySession", "LinkFault", "LinkLimits", "LinkTimeout", "PortInfo", "RateError", "Sample",
           "SequenceError", "Session", "V1Session", "burst_line", "latency_timer", "logger", "open_port",
           "open_session", "port_info", "sim_url"]

_SESSIONS = {"v1": V1Session, "legacy": LegacySession}


def open_session(url: str, protocol: str = "v1", timeout: float = DEFAULT_TIMEOUT, baudrate: int | None = None,
                 limits: LinkLimits | None = None) -> Session:
    """Open ``url`` and return a :class:`Session` of ``protocol`` ("v1" or "legacy").

    Parameters
    ----------
    url, protocol, baudrate
        As :func:`open_port`.
    timeout : float
        Sample timeout, s (``limits.timeout`` wins when ``limits`` is given).
    limits : LinkLimits, optional
        The fail-safe bounds; default ``LinkLimits(timeout)``.

    Returns
    -------
    Session
        A :class:`V1Session` or :class:`LegacySession`; a context manager that closes
        the port.

    Raises
    ------
    StationError
        An unknown protocol or a port that cannot be opened.
    """
    if protocol not in _SESSIONS:
        raise StationError(f"unknown protocol {protocol!r}: expected one of {', '.join(_SESSIONS)}")
    limits = limits or LinkLimits(timeout=timeout)
    url = sim_url(url, protocol)
    port = open_port(url, protocol, min(limits.timeout, POLL_S), baudrate, write_timeout=limits.timeout)
    logger.info("opened %s (%s, %s)", url, protocol, limits)
    return _SESSIONS[protocol](port, url, limits)
