"""Open a device by URL with pyserial, for one protocol.

Any pyserial URL works: a port path (``/dev/ttyACM0``, a pty), ``socket://host:port``,
``loop://`` and our ``sim://`` (the simulated rig, :mod:`station.sim.protocol_sim`),
whose handler package this module registers in ``serial.protocol_handler_packages``
(pyserial's documented hook; by name, so the link never imports the simulator).
"""

from __future__ import annotations

import errno
import logging
import os
import re
from pathlib import Path
from typing import NamedTuple
from urllib.parse import parse_qsl, urlencode, urlsplit

import serial
from serial.tools import list_ports

from station.errors import StationError
from station.protocol import legacy
from station.rig import DEFAULT_TIMEOUT

SIM_HANDLERS = "station.sim"
"""The package that holds ``protocol_sim`` (pyserial finds ``sim://`` there)."""
DEFAULT_BAUD = {"v1": 921600, "legacy": legacy.BAUDRATE}
SYSFS = Path("/sys")
"""Where Linux shows its devices (a test may point it elsewhere)."""

logger = logging.getLogger("station.link")


class PortInfo(NamedTuple):
    """What a port is: the adapter behind it and its latency timer (``station ports``, the run's start line).

    Attributes
    ----------
    device : str
        The port path or URL.
    adapter : str
        pyserial's description of the adapter (e.g. "FT232R USB UART - FT232R USB UART"),
        "pseudo-terminal", "simulated rig" or "" when unknown.
    hwid : str
        pyserial's hardware id (USB VID:PID, serial number), "" when unknown.
    latency : (int, str) or None
        The USB serial adapter's latency timer, ms, and its sysfs file; None when the OS
        shows none.
    low_latency : bool or None
        Whether the OS took the low-latency request (None: not asked, not a serial device).
    """

    device: str
    adapter: str
    hwid: str
    latency: tuple[int, str] | None
    low_latency: bool | None = None

    def to_json(self) -> dict:
        """The log header's ``link``: adapter, hwid, latency_timer_ms, low_latency."""
        return {"adapter": self.adapter, "hwid": self.hwid,
                "latency_timer_ms": None if self.latency is None else self.latency[0], "low_latency": self.low_latency}

    def summary(self) -> str:
        """One phrase: ``/dev/ttyUSB0 (FT232R USB UART, latency timer 1 ms)``."""
        parts = [self.adapter] if self.adapter else []
        if self.latency is not None:
            parts.append(f"latency timer {self.latency[0]} ms")
        if self.low_latency is False:
            parts.append("low-latency mode refused")
        return f"{self.device} ({', '.join(parts)})" if parts else self.device


def _tty_name(device: str) -> str:
    return Path(os.path.realpath(device)).name


def is_pty(device: str) -> bool:
    """Whether a port is a pseudo-terminal (``/dev/pts/N``: a simulated device, a test).

    Parameters
    ----------
    device : str
        A port path (a symlink is followed) or URL.
    """
    return os.path.realpath(device).startswith("/dev/pts/")


def latency_timer(device: str, sysfs: Path | None = None) -> tuple[int, str] | None:
    """The USB serial adapter's latency timer of a port, where the OS shows one.

    Linux's usb-serial drivers (FTDI) show it as
    ``/sys/bus/usb-serial/devices/<tty>/latency_timer``, in ms (default 16; 1 in
    low-latency mode).

    Parameters
    ----------
    device : str
        The port path (a symlink such as ``/dev/serial/by-id/...`` is followed).
    sysfs : Path, optional
        The sysfs root (default :data:`SYSFS`).

    Returns
    -------
    (int, str) or None
        The timer in ms and the file that sets it; None where there is none (a pty,
        CDC ACM, a URL, another OS) or it cannot be read.
    """
    if "://" in device:
        return None
    path = (SYSFS if sysfs is None else sysfs) / "bus" / "usb-serial" / "devices" / _tty_name(device) / "latency_timer"
    try:
        return int(path.read_text().strip()), str(path)
    except (OSError, ValueError):
        return None


def port_info(device: str, low_latency: bool | None = None) -> PortInfo:
    """The adapter and latency timer of a port (pyserial's ``list_ports`` and sysfs).

    Parameters
    ----------
    device : str
        A port path or URL.
    low_latency : bool or None
        Whether the OS took the low-latency request (:func:`open_port` knows), for the summary.
    """
    if device.startswith("sim://"):
        return PortInfo(device, "simulated rig", "", None)
    if "://" in device:
        return PortInfo(device, "", "", None)
    if is_pty(device):
        return PortInfo(device, "pseudo-terminal", "", None)

    real = os.path.realpath(device)
    found = next((p for p in list_ports.comports() if os.path.realpath(p.device) == real), None)
    adapter = found.description if found is not None and found.description not in (None, "n/a") else ""
    hwid = found.hwid if found is not None and found.hwid not in (None, "n/a") else ""
    return PortInfo(device, adapter, hwid, latency_timer(device), low_latency)


def _ask_low_latency(port: serial.SerialBase, url: str) -> bool | None:
    """Ask the OS for low-latency mode on a serial device (pyserial, Linux: FTDI adapters then
    use a 1 ms latency timer); a refusal is a warning. None: not asked (a URL, a pty, no API)."""
    if "://" in url or is_pty(url) or not hasattr(port, "set_low_latency_mode"):
        return None
    try:
        port.set_low_latency_mode(True)
        return True
    except (OSError, ValueError, serial.SerialException, NotImplementedError) as exc:
        logger.warning("%s: the OS refused low-latency mode (%s); samples may arrive in bursts "
                       "(README \"Safety\": the latency timer)", url, exc)
        return False


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


def open_port(url: str, protocol: str = "v1", timeout: float = DEFAULT_TIMEOUT, baudrate: int | None = None,
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

    Returns
    -------
    serial.SerialBase
        The open port; its ``station_info`` (:class:`PortInfo`) names the adapter and its
        latency timer. On a serial device the OS is asked for low-latency mode first
        (pyserial ``set_low_latency_mode``; a refusal is a warning).

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
        port = serial.serial_for_url(url, **kwargs)
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
    port.station_info = port_info(url, _ask_low_latency(port, url))
    return port
