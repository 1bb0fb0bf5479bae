"""Open a device by URL with pyserial, for one protocol.

Any pyserial URL works: a port path (``/dev/ttyACM0``, a pty), ``socket://host:port``,
``loop://`` and our ``sim://`` (the simulated rig, :mod:`station.sim.protocol_sim`),
whose handler package this module registers in ``serial.protocol_handler_packages``
(pyserial's documented hook; by name, so the link never imports the simulator).
"""

from __future__ import annotations

import errno
import os
import re
from urllib.parse import parse_qsl, urlencode, urlsplit

import serial

from station.errors import StationError
from station.protocol import legacy

SIM_HANDLERS = "station.sim"
"""The package that holds ``protocol_sim`` (pyserial finds ``sim://`` there)."""
DEFAULT_BAUD = {"v1": 921600, "legacy": legacy.BAUDRATE}


def sim_url(url: str, protocol: str) -> str:
    """Add ``protocol=`` to a ``sim://`` URL that does not name one; other URLs pass unchanged.

    Parameters
    ----------
    url : str
        A port path or pyserial URL.
    protocol : str
        "v1" or "legacy".
    """
    parts = urlsplit(url)
    if parts.scheme != "sim":
        return url
    # the URL as given, repeats and blanks included: the handler refuses them, naming the option
    if any(name == "protocol" for name, _ in parse_qsl(parts.query, keep_blank_values=True)):
        return url
    return f"{url}{'&' if parts.query else '' if url.endswith('?') else '?'}{urlencode({'protocol': protocol})}"


def open_port(url: str, protocol: str = "v1", timeout: float = 0.1, baudrate: int | None = None,
              write_timeout: float | None = None) -> serial.SerialBase:
    """Open ``url`` with pyserial for one protocol.

    Parameters
    ----------
    url : str
        A port path or pyserial URL (``sim://``, ``socket://``, ``loop://``, ...).
    protocol : {"v1", "legacy"}
        Chooses the default baud rate (921600 / 115200) and, for ``sim://``, the
        simulated device's protocol.
    timeout : float
        Read timeout in s: the longest single blocking read (sessions use
        :data:`station.link.faults.POLL_S` and keep their own deadline per sample).
    write_timeout : float, optional
        The longest a write may block, s (default ``timeout``).
    baudrate : int, optional
        Overrides the protocol's default.

    Raises
    ------
    StationError
        The port is missing, busy (locked by another process) or the URL is invalid;
        the message names the port.
    """
    if SIM_HANDLERS not in serial.protocol_handler_packages:
        serial.protocol_handler_packages.append(SIM_HANDLERS)  # pyserial's documented hook
    url = sim_url(url, protocol)
    kwargs = {"baudrate": baudrate or DEFAULT_BAUD[protocol], "timeout": timeout,
              "write_timeout": timeout if write_timeout is None else write_timeout}
    if "://" not in url:
        kwargs["exclusive"] = True  # a second station on the same rig is an error, not a fight
    try:
        return serial.serial_for_url(url, **kwargs)
    except (serial.SerialException, ValueError, OSError) as exc:
        # pyserial: "Could not exclusively lock port ..." (flock) or EBUSY from open()
        text = str(exc).replace("\n", " ")
        busy = "exclusively lock" in text or getattr(exc, "errno", None) == errno.EBUSY
        code = getattr(exc, "errno", None)
        if busy:
            reason = "port is busy (another program has it open)"
        elif isinstance(code, int) and code in errno.errorcode:
            reason = os.strerror(code)  # pyserial repeats the port in its text; say it once
        else:
            reason = re.sub(rf"(?i)^could not open port {re.escape(url)}:?\s*", "", text) or text
        hint = "; `station ports` lists the serial ports" if "://" not in url else ""
        raise StationError(f"cannot open port {url}: {reason}{hint}", key="port") from None
