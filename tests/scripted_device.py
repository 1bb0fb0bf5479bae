"""A scripted rig on a pty, written from the protocol spec, as an independent test oracle.

It plays the device side of protocol v1 or legacy at 500 Hz on the master end of a pty
(the station opens the slave as a real port), records the wall time each sample was
sent and every command the station wrote, and can misbehave on cue: go silent, send
garbage and corrupted frames, or skip a legacy tick number.
"""

from __future__ import annotations

import os
import pty
import select
import threading
import time
import tty

from station.protocol import legacy, v1


CLOCK_STALL_S = 0.02
"""A tick this late means the device's thread was held up (a loaded or stalled test machine):
the scripted device then failed to be the device the test describes (a rig's clock does not
stall), and the run is no trial of the station."""

LIVE: list = []
"""The scripted devices made in the current test (emptied by the ``device_factory`` fixture)."""


def device_clock_stalled(error=None) -> bool:
    """True when a scripted device of the current test missed its own clock by more than
    :data:`CLOCK_STALL_S`: the condition under which a failed timing test is run again
    (``pytest.mark.flaky(condition=device_clock_stalled)``), since the device, not the
    station, broke the test's premise. A failure on a device that kept its clock stands."""
    return any(dev.clock_stalls for dev in LIVE)


class ScriptedDevice:
    """Device side of a protocol on a pty; start with :meth:`start`, then open ``path``.

    Parameters: protocol "v1" | "legacy"; theta(k) -> encoder counts of tick k;
    silent_after: stop sending after this tick; garbage_every: (v1) garbage + a corrupted
    frame after every N-th sample; skip_at: (legacy) n jumps by one at this tick;
    accel(k) -> accelerometer counts of tick k; after_start: (v1) bytes sent right after
    START, before tick 0; period: s per tick, or period(k) -> s before tick k+1 (a slow or
    fast device); mutate(k, data) -> bytes: what tick k really sends instead of its
    well-formed ``data`` (hostile behaviours: noise, repeats, swaps, byte slips; the wall
    time of the first tick whose bytes it changed is kept in ``fault_time``);
    status(k) -> v1 status bits of tick k; hello_reply(data) -> bytes: the answer to HELLO
    (v1) or 'r' (legacy) instead of INFO / θ; rate_hz: INFO's rate (0 declares lockstep);
    hold(k) -> bool: tick k's bytes are held back and go out together with the next tick
    that is not held (a stalled link, a USB adapter's latency timer: bursts); the wall time
    of each release of held bytes is kept in ``released_at``.
    """

    def __init__(self, protocol="v1", theta=lambda k: 0, silent_after=None, garbage_every=None,
                 skip_at=None, period=0.002, accel=lambda k: 0, after_start=b"", mutate=None,
                 status=lambda k: 0, hello_reply=None, rate_hz=500, hold=None):
        self.protocol = protocol
        self.theta = theta
        self.accel = accel
        self.after_start = after_start  # v1: bytes sent right after START (e.g. a stale sample)
        self.silent_after, self.garbage_every, self.skip_at = silent_after, garbage_every, skip_at
        self.period = period if callable(period) else (lambda k, p=period: p)
        self.mutate, self.status, self.hello_reply, self.rate_hz = mutate, status, hello_reply, rate_hz
        self.fault_time: float | None = None         # wall time (time.time) of the first mutated tick
        self.hold = hold
        self._held: list[tuple[int, bytes]] = []     # ticks held back, not yet written
        self.released_at: list[float] = []           # wall time of each release of held ticks
        self.received_at: list[float] = []            # wall time each entry of ``received`` arrived
        self.master, self.slave = pty.openpty()
        tty.setraw(self.master)
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self.sent: list[tuple[int, float]] = []     # (tick, wall time the sample was written)
        self.received: list = []                     # v1 messages / legacy command tuples, in order
        self.outputs: list[int] = []                 # the output applied at each tick
        self.clock_stalls: list[tuple[float, float]] = []  # (wall time, s late) of ticks the thread missed
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        LIVE.append(self)

    def start(self):
        self._thread.start()
        return self

    def close(self):
        self._stop.set()
        self._thread.join(timeout=2)
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass

    def wait_for(self, predicate, timeout=1.0) -> bool:
        """Poll ``predicate(self)`` until true or ``timeout`` s pass; returns its last value."""
        deadline = time.perf_counter() + timeout
        while not predicate(self) and time.perf_counter() < deadline:
            time.sleep(0.005)
        return predicate(self)

    def commands(self):
        """The (seq or None, v) of every command the station sent, in order."""
        if self.protocol == "v1":
            return [(m.seq, m.v) for m in self.received if isinstance(m, v1.Command)]
        return [(None, c[1]) for c in self.received if c[0] == "/"]

    def _write(self, data: bytes):
        os.write(self.master, data)

    def _run(self):
        try:  # the "hardware" must keep its clock under load (it never stalls on a real rig)
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(20))  # this thread only (Linux)
        except (AttributeError, OSError):
            pass
        decoder = v1.Decoder() if self.protocol == "v1" else legacy.CommandDecoder()
        running, k, next_tick, output, last_cmd = False, 0, 0.0, 0, None
        ideal = 0.0  # when the next tick is due by the device's own schedule
        while not self._stop.is_set():
            timeout = max(0.0, next_tick - time.perf_counter()) if running else 0.01
            try:
                ready, _, _ = select.select([self.master], [], [], timeout)
            except (OSError, ValueError):  # the master end was closed (a vanishing-port test)
                return
            if ready:
                try:
                    data = os.read(self.master, 4096)
                except OSError:
                    return
                for msg in decoder.feed(data):
                    self.received.append(msg)
                    self.received_at.append(time.time())
                    if self.protocol == "v1":
                        if isinstance(msg, v1.Hello):
                            self._write(self.hello_reply(data) if self.hello_reply else
                                        v1.encode(v1.Info(1, 0, 9, 0, self.rate_hz, 255, 1024, 10, "SCRIPTED")))
                        elif isinstance(msg, v1.Start):
                            running, k, next_tick, output, last_cmd = True, 0, time.perf_counter(), 0, None
                            ideal = next_tick
                            if self.after_start:
                                self._write(self.after_start)
                        elif isinstance(msg, v1.Command):
                            last_cmd = msg.v
                        elif isinstance(msg, v1.Stop):
                            running, output = False, 0
                            self.outputs.append(0)
                            self._release()
                            self._write(v1.encode(v1.Stopped(0, k, 0, 0, decoder.rx_errors)))
                    else:
                        if msg[0] == "r":
                            self._write(self.hello_reply(data) if self.hello_reply else legacy.encode_word(0))
                        elif msg[0] == "q":
                            self._write(legacy.encode_word(0))
                            running, k, next_tick, output = True, 0, time.perf_counter(), 0
                            ideal = next_tick
                        elif msg[0] == "/":
                            last_cmd = msg[1]
                        elif msg[0] == "s":
                            running = False
                            self._release()
            if running and (now := time.perf_counter()) >= next_tick:
                if now - ideal > CLOCK_STALL_S:  # behind its own schedule: held up, at once or bit by bit
                    self.clock_stalls.append((time.time(), now - ideal))
                    ideal = now
                ideal += self.period(k + 1)
                if last_cmd is not None:
                    output = last_cmd
                self.outputs.append(output)
                if self.silent_after is None or k <= self.silent_after:
                    self._send_tick(k, output)
                k += 1
                # a stalled test thread (a loaded CI machine) ticks late rather than bursting
                # the missed ticks at once: a real device's clock does not stall
                next_tick = max(next_tick + self.period(k), time.perf_counter() + 0.2 * self.period(k))

    def _release(self):
        """Write what is held back (the link passes it on at the latest when the device stops)."""
        held, self._held = self._held, []
        if held:
            try:
                self._write(b"".join(d for _, d in held))
            except OSError:
                return
            self.sent.extend((j, time.time()) for j, _ in held)

    def _send_tick(self, k, output):
        if self.protocol == "v1":
            data = v1.encode(v1.Sample(k & 0xFFFF, self.theta(k), self.accel(k), output, self.status(k)))
            if self.garbage_every and k and k % self.garbage_every == 0:
                bad = bytearray(v1.encode(v1.Sample(k & 0xFFFF, 99, 0, 0, 0)))
                bad[3] ^= 0x40  # corrupt one byte: CRC fails
                data = b"\x13\x37\xff\x00" + data + bytes(bad)
        else:
            n = k + 1 if self.skip_at is not None and k >= self.skip_at else k
            data = legacy.tick_bytes(legacy.Tick(n, self.theta(k), self.accel(k)))
        if self.mutate is not None:
            real = self.mutate(k, data)
            if real != data and self.fault_time is None:
                self.fault_time = time.time()
            data = real
        if self.hold is not None and self.hold(k):
            self._held.append((k, data))
            return
        ticks = [*self._held, (k, data)]
        self._held = []
        try:
            self._write(b"".join(d for _, d in ticks))
        except OSError:  # the station closed its end
            return
        now = time.time()
        if len(ticks) > 1:
            self.released_at.append(now)
        self.sent.extend((j, now) for j, _ in ticks)

    def stop_time(self) -> float | None:
        """Wall time the station's last stop (v1 STOP, legacy 's') arrived, or None (the last:
        a legacy station stops its accelerometer pre-run with 's' too)."""
        for msg, at in zip(reversed(self.received), reversed(self.received_at)):
            if (isinstance(msg, v1.Stop) if self.protocol == "v1" else msg == ("s",)):
                return at
        return None

    def last_sent(self, count=2):
        """The last ``count`` messages the station sent (v1 messages / legacy command tuples)."""
        return self.received[-count:]


class MemoryPort:
    """An in-memory port for session tests: ``data`` is what has already arrived (all of it),
    ``written`` every write in order; ``on_write(data)`` may answer (e.g. START with samples)."""

    def __init__(self, on_write=None):
        self.data = bytearray()
        self.written: list[bytes] = []
        self.on_write = on_write

    def write(self, data):
        self.written.append(bytes(data))
        if self.on_write is not None:
            self.data += self.on_write(bytes(data))
        return len(data)

    def reset_input_buffer(self):
        pass

    def read(self, size=1):
        out = bytes(self.data[:size])
        del self.data[:size]
        return out

    @property
    def in_waiting(self):
        return len(self.data)
