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


# every script option that names a file the script writes (station.outputs' rules, checked before the work)
OUTPUTS = [("bench_audit.py", "--json"), ("bench_diagnose.py", "--json"), ("bench_loop.py", "--json"),
           ("bench_read.py", "--json"), ("bench_sim.py", "--json"), ("bench_startup.py", "--json"),
           ("bench_tick.py", "--json"), ("bench_tune.py", "--json"), ("heldout_tune.py", "--json"),
           ("identify_hidden.py", "--out"), ("rig_study.py", "--save-model"), ("rig_sweeps.py", "--figure")]


def test_every_script_output_option_is_in_the_list():
    """A script that gains a file option is checked below too (the list is the scripts' own)."""
    options = ("--json", "--out", "--save-model", "--figure", "--png", "--csv")
    found = set()
    for script in SCRIPTS.glob("*.py"):
        text = script.read_text()
        found |= {(script.name, o) for o in options if f'add_argument("{o}"' in text}
    # these three rewrite a section of a Markdown page in place (their input is their output)
    found -= {("tuning_table.py", "--out"), ("validate_audit.py", "--out"), ("validate_diagnosis.py", "--out")}
    assert found == set(OUTPUTS)


@pytest.mark.parametrize("script, option", OUTPUTS)
def test_an_existing_output_is_refused_before_the_work_in_one_line(script, option, tmp_path, capsys):
    main = runpy.run_path(str(SCRIPTS / script), run_name="script_options")["main"]
    existing = tmp_path / "old.out"
    existing.write_text("kept\n")
    with pytest.raises(SystemExit) as exc:
        main([option, str(existing)])
    assert exc.value.code == 2
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"{option} {existing}: exists; use --force" in last
    assert existing.read_text() == "kept\n"
    with pytest.raises(SystemExit) as exc:
        main([option, str(tmp_path)])
    assert exc.value.code == 2
    assert f"{option} {tmp_path}: is a folder" in capsys.readouterr().err.strip().splitlines()[-1]
