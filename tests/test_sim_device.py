"""SimDevice against the protocol spec (shared/spec/protocol.md), on a plant that records its inputs.

StepRecorderPlant: after steps v[0..k-1], theta = sum(v), a = v[k-1]. So sample k's theta
and a tell exactly which outputs acted on the plant before tick k latched its sensors.
"""

import pytest

from station.protocol import legacy, v1
from station.sim.device import SimDevice
from station.sim.standin import RoundingSensors, StepRecorderPlant

OFFSET = -2.0


def make(protocol="v1", **kw):
    kw.setdefault("accel_offset", OFFSET)
    return SimDevice(protocol, plant=StepRecorderPlant(), sensors=RoundingSensors(0, 0.0), **kw)


def frames(data):
    dec = v1.Decoder()
    msgs = dec.feed(data)
    assert dec.rx_errors == 0
    return msgs


def sample(dev):
    (msg,) = frames(dev.tick())
    assert isinstance(msg, v1.Sample)
    return msg


def started(flags=0, n_ticks=0, **kw):
    dev = make(**kw)
    dev.receive(v1.encode(v1.Start(flags, n_ticks)))
    assert dev.take_output() == b""
    return dev


def zeroing(dev):
    """START bit1's 16 ticks: no SAMPLE (spec), the device ready to run them at once."""
    for _ in range(16):
        assert dev.ready and dev.running
        assert dev.tick() == b"" and dev.tick_index == 0


def command(dev, seq, v):
    dev.receive(v1.encode(v1.Command(seq, v)))


def test_hello_is_answered_by_info_at_any_time():
    dev = make()
    dev.receive(v1.encode(v1.Hello()))
    info = frames(dev.take_output())
    assert info == [v1.Info(1, 0, 1, 0, 500, 255, 1024, 10, "SIMRIG")]
    dev.receive(v1.encode(v1.Start(0, 0)))
    sample(dev)
    dev.receive(v1.encode(v1.Hello()))
    assert frames(dev.take_output()) == info


def test_nothing_is_sent_before_start():
    dev = make()
    assert not dev.running
    assert dev.tick() == b""


def test_tick0_outputs_zero_and_is_not_late():
    s = sample(started())
    assert (s.seq, s.v_applied, s.status) == (0, 0, 0)


def test_command_for_k_minus_1_acts_from_tick_k_and_sensors_latch_before_it():
    dev = started()
    s0 = sample(dev)
    command(dev, 0, 7)
    s1 = sample(dev)
    assert (s1.seq, s1.v_applied, s1.status) == (1, 7, 0)
    assert (s1.theta, s1.accel) == (0, 0 + OFFSET)  # only tick 0's output (0) has acted yet
    command(dev, 1, -3)
    s2 = sample(dev)
    assert (s2.v_applied, s2.theta, s2.accel) == (-3, 7, 7 + OFFSET)
    s3 = sample(dev)  # no command: hold -3
    assert (s3.theta, s3.accel) == (4, -3 + OFFSET)
    assert s0.theta == 0


def test_missing_command_holds_last_output_and_sets_late():
    dev = started()
    sample(dev)
    command(dev, 0, 40)
    sample(dev)
    s = sample(dev)
    assert (s.seq, s.v_applied, s.status) == (2, 40, v1.LATE)
    assert dev.late == 1


@pytest.mark.parametrize("wd", [1, 3, 10])
def test_watchdog_from_the_nth_consecutive_miss_then_recovery_counts_one_trip(wd):
    dev = started(watchdog_ticks=wd)
    sample(dev)
    command(dev, 0, 40)
    sample(dev)
    for miss in range(1, wd + 3):
        s = sample(dev)
        if miss < wd:
            assert (s.v_applied, s.status) == (40, v1.LATE), miss
        else:
            assert (s.v_applied, s.status) == (0, v1.LATE | v1.WATCHDOG), miss
    assert dev.watchdog_trips == 0
    command(dev, s.seq, 25)
    s = sample(dev)
    assert (s.v_applied, s.status) == (25, 0)
    assert dev.watchdog_trips == 1
    assert dev.late == wd + 2


def test_output_is_clamped_to_v_limit_with_saturated():
    dev = started()
    sample(dev)
    command(dev, 0, 300)
    s = sample(dev)
    assert (s.v_applied, s.status) == (255, v1.SATURATED)
    command(dev, 1, -1000)
    assert sample(dev).v_applied == -255
    s = sample(dev)  # the held output is the clamped one: no longer saturating
    assert (s.v_applied, s.status) == (-255, v1.LATE)


def test_unexpected_seq_is_ignored_and_flagged_stale_once():
    dev = started()
    sample(dev)
    command(dev, 0, 10)
    sample(dev)
    command(dev, 0, 99)  # answers sample 0 again: stale
    s = sample(dev)
    assert (s.v_applied, s.status) == (10, v1.LATE | v1.STALE)
    command(dev, 2, 5)
    assert sample(dev).status == 0


def test_bad_frame_sets_rx_error_on_the_next_sample_only_and_is_counted():
    dev = started()
    sample(dev)
    bad = bytearray(v1.encode(v1.Command(0, 10)))
    bad[2] ^= 0x40
    dev.receive(bytes(bad) + v1.encode(v1.Command(0, 10)))
    s = sample(dev)
    assert (s.v_applied, s.status) == (10, v1.RX_ERROR)
    command(dev, 1, 10)
    assert sample(dev).status == 0
    assert dev.rx_errors == 1


def test_stop_outputs_zero_at_once_and_answers_stopped_with_counters():
    dev = started()
    sample(dev)
    sample(dev)  # late
    dev.receive(b"\x05\x00")  # a bad frame
    dev.receive(v1.encode(v1.Stop()))
    assert frames(dev.take_output()) == [v1.Stopped(0, 2, 1, 0, 1)]
    assert not dev.running
    assert dev.tick() == b""


def test_n_ticks_ends_with_stopped_reason_1_after_the_last_sample():
    dev = started(n_ticks=3)
    out = [dev.tick() for _ in range(3)]
    assert [type(m) for m in frames(out[2])] == [v1.Sample, v1.Stopped]
    assert frames(out[2])[1] == v1.Stopped(1, 3, 2, 0, 0)
    assert not dev.running and dev.tick() == b""


def test_start_zeroes_accelerometer_offset_and_encoder():
    raw = started(0)
    assert sample(raw).accel == OFFSET
    dev = started(v1.START_ZERO_ACCEL | v1.START_RESET_ENCODER)
    zeroing(dev)
    assert sample(dev).accel == 0
    # the encoder: move, then restart with bit0
    command(dev, 0, 50)
    sample(dev)
    assert sample(dev).theta == 50
    dev.receive(v1.encode(v1.Start(v1.START_RESET_ENCODER, 0)))
    s = sample(dev)
    assert (s.seq, s.theta) == (0, 0)


def test_zeroing_averages_sixteen_noisy_readings():
    dev = SimDevice(plant=StepRecorderPlant(), sensors=RoundingSensors(1, 0.3), accel_offset=-2.0)
    dev.receive(v1.encode(v1.Start(v1.START_ZERO_ACCEL, 0)))
    zeroing(dev)
    mean = sum(sample(dev).accel for _ in range(200)) / 200
    assert abs(mean) < 0.2


def test_counters_reset_at_start():
    dev = started()
    sample(dev)
    sample(dev)
    assert (dev.ticks, dev.late) == (2, 1)
    dev.receive(v1.encode(v1.Start(0, 0)))
    assert (dev.ticks, dev.late) == (0, 0)


def test_lockstep_readiness():
    dev = make()
    assert not dev.ready
    dev.receive(v1.encode(v1.Start(0, 0)))
    assert dev.ready
    sample(dev)
    assert not dev.ready
    command(dev, 0, 1)
    assert dev.ready


def test_unknown_protocol_is_an_error():
    with pytest.raises(ValueError, match="protocol"):
        make("v2")


# -- legacy ----------------------------------------------------------------------

def ticks(data):
    dec = legacy.TickDecoder()
    out = dec.feed(data)
    assert dec.pending == 0
    return out


def test_legacy_q_answers_theta0_then_ticks_n_theta_a():
    dev = make("legacy")
    dev.receive(legacy.RESET)
    dev.receive(legacy.START)
    assert dev.take_output() == legacy.encode_word(0)
    assert dev.running
    assert ticks(dev.tick()) == [legacy.Tick(0, 0, -2)]
    dev.receive(legacy.command_bytes(30.9))  # truncated by the station: 30
    assert ticks(dev.tick()) == [legacy.Tick(1, 0, -2)]  # latched before 30 acts
    assert ticks(dev.tick()) == [legacy.Tick(2, 30, 30 - 2)]  # no '/': the last v stays
    assert ticks(dev.tick()) == [legacy.Tick(3, 60, 30 - 2)]
    assert dev.late == 2


def test_legacy_r_reads_theta_and_7_zeroes_it():
    dev = make("legacy")
    dev.receive(legacy.START)
    dev.take_output()
    dev.receive(legacy.command_bytes(12))
    dev.tick()  # tick 0 applies the last v received, like every tick
    dev.tick()
    dev.receive(legacy.READ)
    assert dev.take_output() == legacy.encode_word(24)
    dev.receive(legacy.RESET + legacy.READ)
    assert dev.take_output() == legacy.encode_word(0)


def test_legacy_s_stops_sending_and_has_no_watchdog():
    dev = make("legacy")
    dev.receive(legacy.START + legacy.command_bytes(-20))
    dev.take_output()
    for _ in range(30):
        dev.tick()
    assert ticks(dev.tick())[0].accel == -20 - 2  # still applied, 30 ticks without '/'
    dev.receive(legacy.command_bytes(0) + legacy.STOP)
    assert not dev.running
    assert dev.tick() == b"" and dev.take_output() == b""


def test_legacy_unknown_bytes_are_counted():
    dev = make("legacy")
    dev.receive(legacy.START)
    dev.receive(b"xz")
    assert dev.rx_errors == 2


# -- the FEM plant (default) ------------------------------------------------------

def test_fem_plant_constant_positive_v_moves_theta_up_and_the_tip_first_lags():
    dev = SimDevice(seed=0, accel_noise_std=0.0)
    dev.receive(v1.encode(v1.Start(v1.START_ZERO_ACCEL | v1.START_RESET_ENCODER, 0)))
    zeroing(dev)
    theta, accel = [], []
    for k in range(101):  # 0.2 s of v = +50
        s = sample(dev)
        theta.append(s.theta)
        accel.append(s.accel)
        command(dev, k, 50)
    assert theta[0] == 0 and accel[0] == 0
    assert theta[-1] > 20
    assert all(b >= a for a, b in zip(theta, theta[1:]))
    first = next(a for a in accel if a != 0)
    assert first < 0  # the tip lags: it first accelerates away from increasing theta
    assert max(accel) > 5  # then follows


def test_stopped_reports_late_and_watchdog_trips_of_the_run():
    dev = started(watchdog_ticks=2)
    sample(dev)
    for _ in range(3):
        s = sample(dev)  # misses 1..3: trip from the 2nd
    command(dev, s.seq, 1)
    sample(dev)
    dev.receive(v1.encode(v1.Stop()))
    assert frames(dev.take_output()) == [v1.Stopped(0, 5, 3, 1, 0)]
