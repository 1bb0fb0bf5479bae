"""``station modes``: the model's modal numbers converge with n and are set beside the rig's."""

import json
import re

import pytest

from station.cli import main


def test_modes_converge_and_compare_with_the_rig(tmp_path, capsys):
    out = tmp_path / "modes.json"
    assert main(["modes", "--elements", "2", "10", "50", "100", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    models = {m["n_elements"]: m for m in json.loads(out.read_text())["models"]}
    # the comparison line: the finest model's antiresonances as the JSON holds them, and no
    # percentage against DESIGN.md's rounded "≈ 2.5" (the rig's sweep measures 2.56 Hz, above
    # the model's 2.55: a percentage against 2.5 would put it below)
    line = next(x for x in text.splitlines() if x.startswith("model (n = 100) antiresonances "))
    printed = [float(x) for x in re.findall(r"(\d+\.\d{3})", line)]
    assert printed == pytest.approx(models[100]["antiresonances_hz"], abs=5e-4) and "%" not in line
    assert "station bode" in line
    for key in ("frequencies_hz", "antiresonances_hz"):
        coarse, fine, finest = (models[n][key][1] for n in (2, 50, 100))
        assert abs(fine - finest) < 1e-3 < abs(coarse - finest)  # converged by 50, not at 2
    # the first antiresonance (hub-held first beam mode) is the rig's 2.52 Hz within 2 %
    assert abs(models[100]["antiresonances_hz"][0] / 2.52 - 1) < 0.02
    assert 0.004 < models[100]["antiresonance_damping"][0] < 0.006  # tmm-fit: 0.0054, rig ≈ 0.005


def test_modes_rejects_bad_element_count(capsys):
    assert main(["modes", "--elements", "0"]) == 2
    assert "argument --elements: 0 is out of range (expected range 1..100" in capsys.readouterr().err
