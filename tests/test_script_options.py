"""The benchmark and study scripts refuse a non-finite or out-of-range number before anything
runs: argparse exits 2 with one line naming the option and its range (station.ranges)."""

import runpy
from pathlib import Path

import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"

BAD = [
    ("bench_tick.py", "--seconds", "nan"), ("bench_tick.py", "--seconds", "0.5"), ("bench_tick.py", "--runs", "0"),
    ("bench_tick.py", "--rounds", "inf"),
    ("held_ticks.py", "--fractions", "nan"), ("held_ticks.py", "--fractions", "1.5"), ("held_ticks.py", "--seeds", "0"),
    ("bench_loop.py", "--burn", "-1"), ("bench_loop.py", "--seconds", "inf"), ("bench_loop.py", "--repeat", "0"),
    ("bench_loop.py", "--max-lag", "nan"),
    ("validate_diagnosis.py", "--seed-list", "inf"), ("validate_diagnosis.py", "--seeds", "0"),
    ("validate_diagnosis.py", "--jobs", "1.5"),
]


@pytest.mark.parametrize("script, option, value", BAD)
def test_a_bad_number_is_one_line_naming_the_option(script, option, value, capsys):
    main = runpy.run_path(str(SCRIPTS / script), run_name="script_options")["main"]
    with pytest.raises(SystemExit) as exc:
        main([option, value])
    assert exc.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"argument {option}: {value} is" in last and "expected range" in last
