"""pyserial URL handler ``sim://``: the simulated SFLR rig, opened like a real port.

``serial.serial_for_url("sim://?protocol=v1&seed=3")`` finds this module once
``"station.sim"`` is in ``serial.protocol_handler_packages`` (``station.link`` adds it).
The device is :class:`station.sim.device.SimDevice` on the FEM plant, driven by
:class:`station.sim.driver.DeviceDriver`.

URL format: ``sim://[?option=value[&option=value...]]``

options:

- ``protocol=v1|legacy``: the firmware's protocol (default ``v1``).
- ``pacing=lockstep|realtime``: ``lockstep`` (default) ticks as fast as the station
  answers: after START (legacy 'q') tick 0 is sent at once and each command for the
  current sample (legacy: each '/') makes the next tick happen inside ``write``;
  ``realtime`` ticks every 2 ms on its own clock thread (absolute deadlines) and never
  waits for the station: missing commands give LATE / hold / WATCHDOG as on the rig.
- ``seed=N``: seed of the sensor noise and of injected garbage, 0..2^32-1 (default 0).
- ``model=NAME|FILE``: the simulated rig's model: a built-in model's name
  (``station/plant/models``) or a model file (DESIGN.md "Model file"), effects included
  (default ``tmm-fit``, the nominal FEM).
- ``elements=N``: FEM element count of the plant, 1..100 (default: the model's, 4).
- ``noise=STD``: accelerometer noise std, 0..100 ADC counts (default 0.3).
- ``watchdog=N``: v1 watchdog_ticks, 1..255 (default 10).
- ``silent_after=N``: fault: nothing is sent after tick N (0..2^32-1) of a run; the
  device keeps running.
- ``garbage_every=N``: fault, v1: after every N-th sample (1..2^32-1), random bytes and
  a frame with a bad CRC (two rx errors for the station). Ignored by legacy.
- ``skip_tick=N``: fault, legacy: n jumps by one at tick N (0..2^32-1; a lost record).
  Ignored by v1.
- ``logging=debug|info|warning|error``: level of the ``station.sim`` logger (as
  pyserial's ``loop://?logging=debug``): debug shows every byte in and out.

The numbers' ranges are :data:`station.ranges.SIM_RIG`'s, the same that ``--seed`` and
``--elements`` check. An unknown option, a repeated option, a blank value (``seed=``) or
a value outside its range raises ``serial.SerialException`` naming the option, before
anything is built. The baud rate and the line settings are accepted and ignored.

Reads: ``read(size)`` returns as soon as ``size`` bytes are there, or when ``timeout``
runs out with what there is; in lockstep pacing nothing can arrive between writes, so a
read returns at once what is buffered when it is not empty. ``in_waiting``,
``reset_input_buffer`` and ``write`` behave as on a port.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
import urllib.parse

from serial.serialutil import PortNotOpenError, SerialBase, SerialException, to_bytes

from station.errors import StationError
from station.plant.model import load_model
from station.protocol import PROTOCOLS
from station.ranges import SIM_RIG, shown
from station.rig import RATE_HZ
from station.sim.device import SimDevice
from station.sim.driver import DeviceDriver, Faults

LOGGER_LEVELS = {"debug": logging.DEBUG, "info": logging.INFO, "warning": logging.WARNING, "error": logging.ERROR}
"""``logging=`` levels of the URL, as pyserial's own handlers (``loop://?logging=debug``)."""

logger = logging.getLogger("station.sim")

_FORMAT = ('expected "sim://[?protocol=v1|legacy&pacing=lockstep|realtime&seed=N&model=NAME|FILE&elements=N&noise=STD'
           '&watchdog=N&silent_after=N&garbage_every=N&skip_tick=N&logging=LEVEL]"')


def _choice(*allowed: str):
    def parse(text: str) -> str:
        if text not in allowed:
            raise ValueError(f"expected one of {', '.join(allowed)}")
        return text
    return parse


_OPTIONS = {  # name: (parser, default); the numbers' ranges are station.ranges.SIM_RIG's (--seed, --elements)
    "protocol": (_choice(*PROTOCOLS), "v1"),
    "pacing": (_choice("lockstep", "realtime"), "lockstep"),
    "seed": (SIM_RIG["seed"], 0),
    "model": (str, "tmm-fit"),  # read and checked with the element count, at the end of parse_url
    "elements": (SIM_RIG["elements"], 4),
    "noise": (SIM_RIG["noise"], 0.3),
    "watchdog": (SIM_RIG["watchdog"], 10),
    "silent_after": (SIM_RIG["silent_after"], None),
    "garbage_every": (SIM_RIG["garbage_every"], None),
    "skip_tick": (SIM_RIG["skip_tick"], None),
    "logging": (_choice(*LOGGER_LEVELS), None),
}


class OptionError(SerialException):
    """A ``sim://`` option with a bad value: ``sim:// option NAME='VALUE': DETAIL``.

    Parameters
    ----------
    option : str
        The option's name.
    value : str
        Its value as given.
    detail : str
        What is wrong and what was expected (the range, or the model file's own error).
    """

    def __init__(self, option: str, value: str, detail: str):
        super().__init__(f"sim:// option {option}={shown(value)}: {detail}")
        self.option, self.value, self.detail = option, value, detail


def parse_url(url: str) -> dict:
    """The options of a ``sim://`` URL, defaults filled in.

    Parameters
    ----------
    url : str
        ``sim://[?option=value&...]`` (options: the module docstring).

    Returns
    -------
    dict
        Every option by name, parsed, defaults filled in.

    Raises
    ------
    serial.SerialException
        Not a ``sim://`` URL, unknown or repeated option; :class:`OptionError` (one) for a
        bad value. The message names the option.
    """
    parts = urllib.parse.urlsplit(url)
    if parts.scheme.lower() != "sim":
        raise SerialException(f"{_FORMAT}: not starting with sim:// ({url!r})")
    if parts.netloc or parts.path not in ("", "/"):
        raise SerialException(f"{_FORMAT}: unexpected {parts.netloc + parts.path!r} before '?'")
    opts = {name: default for name, (_, default) in _OPTIONS.items()}
    seen = set()
    for name, value in urllib.parse.parse_qsl(parts.query, keep_blank_values=True, strict_parsing=False):
        if name not in _OPTIONS:
            raise SerialException(f"{_FORMAT}: unknown option {shown(name)}")
        if name in seen:
            raise SerialException(f"sim:// option {name}: given twice (give each option once)")
        seen.add(name)
        try:
            opts[name] = _OPTIONS[name][0](value)
        except ValueError as e:  # (a RangeError is one)
            raise OptionError(name, value, str(e)) from None
    if "model" in seen or "elements" in seen:
        try:  # bounded: a regular file of at most 1 MB, every field in its range, for this element count
            model = load_model(opts["model"], n_elements=opts["elements"] if "elements" in seen else None)
        except StationError as exc:
            raise OptionError("model", opts["model"], str(exc)) from None
        opts["elements"] = model.n_elements
    return opts


class Serial(SerialBase):
    """The simulated rig behind a pyserial port (see the module docstring for the URL).

    Parameters
    ----------
    *args, **kwargs
        As :class:`serial.SerialBase` (``port`` is the ``sim://`` URL); opened at once
        when a port is given, as pyserial does.
    """

    def __init__(self, *args, **kwargs) -> None:
        self._debug = False
        self._buf = bytearray()
        self._cond = threading.Condition()
        self._driver: DeviceDriver | None = None
        self._clock: threading.Thread | None = None
        self._closing = threading.Event()
        self.options: dict = {}
        self.model = None
        super().__init__(*args, **kwargs)

    # -- open / close ------------------------------------------------------------

    def open(self) -> None:
        """Build the device from the URL's options; realtime pacing starts its clock thread."""
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        self.from_url(self.port)
        o = self.options
        if o["logging"] is not None:
            logger.setLevel(LOGGER_LEVELS[o["logging"]])
            if not any(h for lg in (logger, logger.parent) for h in lg.handlers):  # nobody shows it yet
                handler = logging.StreamHandler()
                handler.setFormatter(logging.Formatter("%(name)s: %(message)s"))
                logger.addHandler(handler)
        self._debug = logger.isEnabledFor(logging.DEBUG)

        self.model = load_model(o["model"], n_elements=o["elements"])
        device = SimDevice(o["protocol"], seed=o["seed"], model=self.model,
                           accel_noise_std=o["noise"], watchdog_ticks=o["watchdog"])
        faults = Faults(o["silent_after"], o["garbage_every"], o["skip_tick"], seed=o["seed"])
        self._driver = DeviceDriver(device, faults, lockstep=o["pacing"] == "lockstep")
        self._buf.clear()
        self._closing.clear()
        self.is_open = True
        if o["pacing"] == "realtime":
            self._clock = threading.Thread(target=self._run_clock, name="sim-clock", daemon=True)
            self._clock.start()

    @property
    def paced_by_host(self) -> bool:
        """True in lockstep pacing: the device ticks when the station answers, so it has no
        rate of its own to check (the legacy protocol cannot say so; v1 says it in INFO)."""
        return self._driver is not None and self._driver.lockstep

    def from_url(self, url: str) -> None:
        """Parse ``url`` into :attr:`options` (the one place options are read); see :func:`parse_url`.

        Parameters
        ----------
        url : str
            The ``sim://`` URL.
        """
        self.options = parse_url(url)

    def close(self) -> None:
        """Stop the clock thread (realtime) and wake any blocked read."""
        if self.is_open:
            self.is_open = False
            self._closing.set()
            with self._cond:
                self._cond.notify_all()
            if self._clock is not None and self._clock is not threading.current_thread():
                self._clock.join()
            self._clock = None
        super().close()

    def _reconfigure_port(self) -> None:
        """Baud rate and line settings do not matter to the simulation."""

    @property
    def device(self) -> SimDevice:
        """The simulated device (for tests and benchmarks: counters, plant)."""
        if self._driver is None:
            raise PortNotOpenError()
        return self._driver.device

    @property
    def plant_meta(self) -> dict:
        """What this simulated rig is, for run-log headers: the FEM plant's parameters
        (SI, DESIGN.md names), element count, sample time, the model (name, params,
        effects: :meth:`station.plant.model.Model.to_json`) and the URL's options."""
        plant = self.device.plant
        params = getattr(plant, "params", None)
        return {"model": None if self.model is None else self.model.to_json(),
                "n_elements": getattr(plant, "n_elements", self.options["elements"]),
                "dt": getattr(plant, "dt", None),
                "params": None if params is None else dataclasses.asdict(params),
                "options": dict(self.options)}

    # -- the clock ---------------------------------------------------------------

    def _run_clock(self) -> None:
        """500 Hz ticks on absolute deadlines; a late wake-up runs the missed ticks at once."""
        period = 1.0 / RATE_HZ
        deadline = time.perf_counter() + period
        while not self._closing.is_set():
            delay = deadline - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            with self._cond:
                out = self._driver.clock_tick()
                if out:
                    self._buf += out
                    self._cond.notify_all()
            deadline += period

    # -- port interface ----------------------------------------------------------

    @property
    def in_waiting(self) -> int:
        """Bytes the device has sent that have not been read."""
        if not self.is_open:
            raise PortNotOpenError()
        return len(self._buf)

    def read(self, size: int = 1) -> bytes:
        """Up to ``size`` bytes: waits until there are ``size`` or ``timeout`` runs out (None: no limit).

        Parameters
        ----------
        size : int, default 1
            Most bytes to return.
        """
        if not self.is_open:
            raise PortNotOpenError()
        lockstep = self._driver.lockstep
        with self._cond:
            self._cond.wait_for(
                lambda: len(self._buf) >= size or (lockstep and self._buf) or not self.is_open,
                timeout=self._timeout)
            data = bytes(self._buf[:size])
            del self._buf[:size]
        if self._debug and data:
            logger.debug("device -> station %s", data.hex(" "))
        return data

    def write(self, data) -> int:
        """Send ``data`` to the device; in lockstep, the ticks it triggers are sent before this returns.

        Parameters
        ----------
        data : bytes-like
            Bytes from the station.

        Returns
        -------
        int
            ``len(data)``.
        """
        if not self.is_open:
            raise PortNotOpenError()
        data = to_bytes(data)
        if self._debug:
            logger.debug("station -> device %s", data.hex(" "))
        with self._cond:
            out = self._driver.feed(data)
            if out:
                self._buf += out
                self._cond.notify_all()
        return len(data)

    def reset_input_buffer(self) -> None:
        """Discard what the device has sent and was not read."""
        if not self.is_open:
            raise PortNotOpenError()
        with self._cond:
            self._buf.clear()

    def reset_output_buffer(self) -> None:
        """Nothing is ever pending towards the device: writes reach it at once."""
        if not self.is_open:
            raise PortNotOpenError()

    @property
    def out_waiting(self) -> int:
        """Always 0 (writes reach the device at once)."""
        return 0

    def _update_break_state(self) -> None:
        pass

    def _update_rts_state(self) -> None:
        pass

    def _update_dtr_state(self) -> None:
        pass

    @property
    def cts(self) -> bool:
        return True

    @property
    def dsr(self) -> bool:
        return True

    @property
    def ri(self) -> bool:
        return False

    @property
    def cd(self) -> bool:
        return True
