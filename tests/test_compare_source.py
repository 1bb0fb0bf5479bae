"""compare labels a log by its source and shows the thesis's rows for the thesis's logs only;
open loop, u (DAC counts) has its own axis."""

from __future__ import annotations

import json

from station.compare import compare_run, format_comparison
from station.plots import plot_comparison
from station.cli import main
from station.experiment import run_step
from station.plant.model import load_model

P_STEP = "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt"
PULSE = "OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt"


def test_thesis_rows_for_the_thesis_log_only(rig_data, tmp_path, capsys):
    ours = run_step(controller="p", amplitude=50, out=tmp_path / "p.tsv", figure=False).log_path
    rig = compare_run(rig_data / P_STEP, load_model())
    sim = compare_run(ours, load_model())
    assert (rig.source, sim.source) == ("rig", "simulated")
    assert rig.thesis_experiment is not None and sim.thesis_experiment is None
    assert "thesis FEM" in format_comparison(rig)
    assert "thesis FEM" not in format_comparison(sim) and "thesis experiment" not in format_comparison(sim)
    # each settling (1 %) said with where it counts from (a new user met 1.092 s and 1.172 s for one response)
    assert "settling (1 %) s: from t = 0 of the log (the thesis's definition; this log's step at 0.100 s)" \
        in format_comparison(rig)
    assert "simulated (this log)" in format_comparison(sim) and "outcome completed" in format_comparison(sim)
    out = tmp_path / "c.json"
    assert main(["compare", str(rig_data / P_STEP), str(ours), "--out-dir", str(tmp_path), "--json", str(out)]) == 0
    runs = json.loads(out.read_text())["runs"]
    assert [r["source"] for r in runs] == ["rig", "simulated"]
    assert runs[0]["rig"]["overshoot_pct"] == 24.0 and runs[1]["rig"] is not None and runs[1]["model"] is not None
    assert runs[1]["outcome"]["reason"] == "completed" and runs[0]["outcome"] is None


def test_open_loop_figure_puts_u_on_its_own_axis(rig_data, tmp_path):
    c = compare_run(rig_data / PULSE, load_model())
    fig = plot_comparison(c, tmp_path / "pulse.png")
    assert (tmp_path / "pulse.png").stat().st_size > 0
    twin = [ax for ax in fig.axes if ax.get_ylabel() == "u (DAC counts)"]
    assert len(twin) == 1 and [ln.get_label() for ln in twin[0].get_lines()] == ["u"]
    assert all("u" != ln.get_label() for ln in fig.axes[0].get_lines())
