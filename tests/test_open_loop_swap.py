"""θ and a swapped in an open-loop run: the sensors say which column is which.

The class of defect: a column line is a claim, and the audit checked it only by a closed-loop
law (a swap that makes the law reproduce v). An open-loop run (v = u) has no law that reads θ
or a, so the rig's own open-loop pulses with θ and a written in each other's place were taken
as named: "moving at t = 0 (a copy cut from a longer run)", "a is no tip acceleration", "the
logged v did not move the hub", and a θ fit of -529 %. The invariant: where no law decides,
the sensors do (the encoder at rest reads one count, the hub's angle follows the nominal
model's driven by the logged command), and no log that is as named is read swapped.

Truth: the rig's own logs (``../shared/data/rig``) and the blind generator (``tests.blind``:
its own FEM, friction and sensors, a reversed accelerometer and motor among them).
"""

from __future__ import annotations

import numpy as np
import pytest

from station.logged import LoggedRun
from station.replay import replay
from tests.blind.generator import write_case

PULSES = "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"
SWAP = "θ and a swapped"


def _swap_file(src, dst):
    """``src`` with its θ and a columns (the fifth and sixth) exchanged."""
    lines = src.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = np.array([[float(x) for x in ln.split()] for ln in lines if ln and not ln.startswith("#")])
    rows[:, [4, 5]] = rows[:, [5, 4]]
    dst.write_text("\n".join(head + ["\t".join(f"{x:.12g}" for x in r) for r in rows]) + "\n")
    return dst


def _swaps(run: LoggedRun) -> list[str]:
    return [c.data for c in run.audit.claims if c.claim == "columns" and c.data.endswith(" swapped")]


def test_the_rigs_open_loop_pulses_swapped_are_read_back(rig_data, tmp_path):
    src = rig_data / PULSES
    path = _swap_file(src, tmp_path / PULSES)
    run, clean = LoggedRun.from_path(path), LoggedRun.from_path(src)
    assert _swaps(run) == [SWAP]
    assert run.audit.lines() == [f"header: θ and a as the column line names them; data: {SWAP}"]
    assert np.array_equal(run.data["theta"], clean.data["theta"]) and np.array_equal(run.data["a"], clean.data["a"])
    assert replay(path).fit_pct == replay(src).fit_pct


EFFECTS = [{}, {"coulomb_friction": 8.0}, {"accel_gain": -1.2}, {"motor_polarity": -1.0},
           {"param:drive_c": 2.0, "amp_offset": -2.0}]


@pytest.mark.parametrize("seed", range(len(EFFECTS)))
def test_blind_open_loop_pulses_swapped_are_read_back_and_as_named_are_not(tmp_path, seed):
    """The blind generator's open-loop pulses (a rig with friction, a reversed accelerometer or
    motor, drive damping and an amplifier offset): swapped, said and read back; as written,
    no swap said."""
    effects = EFFECTS[seed]
    path = write_case(tmp_path / "case", effects, seed)[3]
    assert _swaps(LoggedRun.from_path(path)) == [], effects
    run = LoggedRun.from_path(_swap_file(path, tmp_path / path.name))
    assert _swaps(run) == [SWAP], effects
    assert np.array_equal(run.data["theta"], LoggedRun.from_path(path).data["theta"])


def test_no_log_of_the_rigs_is_read_swapped(rig_data):
    """Every log of the rig's in ``../shared`` is as its column line names it."""
    paths = sorted(rig_data.rglob("*.txt"))
    assert len(paths) >= 11
    for path in paths:
        assert _swaps(LoggedRun.from_path(path)) == [], path.name


def test_a_closed_loop_run_is_left_to_its_law(rig_data, tmp_path):
    """A closed-loop run is not asked the sensors' question: its law decides (the P step with θ
    and a swapped is found swapped by the law, once)."""
    name = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
    run = LoggedRun.from_path(_swap_file(rig_data / name, tmp_path / name))
    (claim,) = [c for c in run.audit.claims if c.data == SWAP]
    assert "the header's law" in claim.evidence
