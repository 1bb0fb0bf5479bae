"""Protocol codecs against the shared v1 vectors and the legacy spec."""

import random

import pytest

from station.protocol import legacy, v1

_CLASSES = {
    "SAMPLE": v1.Sample, "COMMAND": v1.Command, "HELLO": v1.Hello, "INFO": v1.Info,
    "START": v1.Start, "STOP": v1.Stop, "STOPPED": v1.Stopped,
}


def _msg(vector):
    return _CLASSES[vector["type"]](**vector["fields"])


def _describe(msg):
    name = {v: k for k, v in _CLASSES.items()}[type(msg)]
    fields = " ".join(f"{k}={getattr(msg, k)}" for k in msg.__dataclass_fields__)
    return f"{name} {fields}".strip()


def test_every_valid_vector_encodes_exactly(v1_vectors):
    for vec in v1_vectors["valid"]:
        assert v1.encode(_msg(vec)).hex() == vec["frame_hex"], vec["type"]


def test_every_valid_vector_decodes_exactly(v1_vectors):
    for vec in v1_vectors["valid"]:
        dec = v1.Decoder()
        assert dec.feed(bytes.fromhex(vec["frame_hex"])) == [_msg(vec)]
        assert dec.rx_errors == 0


def test_invalid_vectors_yield_nothing_and_count(v1_vectors):
    for vec in v1_vectors["invalid"]:
        dec = v1.Decoder()
        assert dec.feed(bytes.fromhex(vec["frame_hex"])) == [], vec["why"]
        expected = 0 if vec["why"] == "empty frame" else 1
        assert dec.rx_errors == expected, vec["why"]


@pytest.mark.parametrize("chunk", [1, 2, 3, 7, 1000])
def test_stream_vector_resynchronises_in_any_split(v1_vectors, chunk):
    stream = bytes.fromhex(v1_vectors["stream"]["bytes_hex"])
    dec = v1.Decoder()
    out = []
    for i in range(0, len(stream), chunk):
        out += dec.feed(stream[i:i + chunk])
    assert [_describe(m) for m in out] == v1_vectors["stream"]["decoded"]
    assert dec.rx_errors == 2  # the garbage and the corrupted frame


def test_decoder_survives_random_bytes_and_recovers():
    rng = random.Random(1)
    dec = v1.Decoder()
    for _ in range(2000):
        dec.feed(bytes(rng.randrange(256) for _ in range(rng.randrange(1, 90))))
    good = v1.Sample(7, -5, 3, 12, v1.LATE)
    assert dec.feed(b"\x00" + v1.encode(good)) == [good]


def test_overlong_frame_is_dropped_and_counted():
    dec = v1.Decoder()
    assert dec.feed(b"\x05" * 200 + b"\x00") == []
    assert dec.rx_errors == 1
    cmd = v1.Command(1, 2)
    assert dec.feed(v1.encode(cmd)) == [cmd]


def test_crc_is_ccitt_false():
    assert v1.crc16(b"123456789") == 0x29B1  # the catalogue check value


@pytest.mark.parametrize("v, expected", [
    (0.5, 1), (-0.5, -1), (1.4999, 1), (-2.5, -3), (199.6, 200), (1e9, 32767), (-1e9, -32768),
    (float("inf"), 32767), (0.49999999999999994, 0), (-0.49999999999999994, 0), (32766.5, 32767),
    (-0.0, 0), (1e-300, 0)])
def test_round_command_halves_away_from_zero(v, expected):
    assert v1.round_command(v) == expected


def test_round_command_rejects_nan():
    with pytest.raises(ValueError):
        v1.round_command(float("nan"))


def test_legacy_words_are_big_endian_twos_complement():
    assert legacy.encode_word(-2) == b"\xff\xfe"
    assert legacy.encode_word(258) == b"\x01\x02"
    assert legacy.command_bytes(-199.9) == b"/\xff\x39"  # truncated toward zero: -199
    assert legacy.command_bytes(1e6) == b"/\x7f\xff"


def test_legacy_tick_decoder_splits_records_across_reads():
    stream = b"".join(legacy.tick_bytes(legacy.Tick(n, 10 * n, -n)) for n in range(5))
    dec = legacy.TickDecoder()
    out = dec.feed(stream[:7]) + dec.feed(stream[7:20]) + dec.feed(stream[20:])
    assert out == [legacy.Tick(n, 10 * n, -n) for n in range(5)]
    assert dec.pending == 0


def test_legacy_command_decoder_parses_and_counts_garbage():
    dec = legacy.CommandDecoder()
    data = b"q7" + legacy.command_bytes(-17) + b"x" + b"r" + legacy.command_bytes(200) + b"s"
    out = dec.feed(data[:3]) + dec.feed(data[3:])
    assert out == [("q",), ("7",), ("/", -17), ("r",), ("/", 200), ("s",)]
    assert dec.errors == 1
