"""Write a blind test case: the rig's four 2 s runs with hidden effects, in the rig's log format.

The runs (like ../shared/data/rig): P control kp = 2, step of 50 at t = 0.1 s; lead Gth,
step of 100 at 0.02 s (clamp +-200); lead Gth + accelerometer Ga, step of 200 at 0.02 s;
open loop, v = +100 for 0.1 s from 0.04 s and -100 for 0.1 s from 1.4 s. Beside a case, a
fifth run (:func:`write_sweep`), like the rig's 2014 sweeps: P control kp = 1, 21 s, the
reference 50 sin(2 pi (t - 0.5)^2) from t = 0.5 s for 20 s (0-40 Hz). The header and
column lines copy the rig's lab software (``#SLFR RTP ...``, ``#kp=2.0``, ``#Gth num=[...]``
printed by numpy to 8 decimals); numbers are printed with 10 significant digits.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tests.blind.rig import DT, Run, ga_design, gth_design, simulate

N = 1000
"""Samples per run (2 s at 500 Hz)."""

COLUMNS = "#t\tn\tu\tv\t$\\theta$\ta"
COLUMNS_ACCEL = COLUMNS + "\t$\\hat{\\theta}_d$"

RUNS = ("p_step", "lead_step", "lead_accel_step", "open_loop_pulses")
"""The runs of a case, in the order :func:`write_case` returns their paths."""

FILES = {
    "p_step": "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
    "lead_step": "step_response_Gth_comp_no_accel_FB_amp_100_SLFR_RTP_Motor_Comp_Gth.txt",
    "lead_accel_step": "step_response_Gth_comp_Ga_amp_200_SLFR_RTP_Motor_Comp_Gth.txt",
    "open_loop_pulses": "OL_pulse_test_SLFR_RTP_OL_Test_uend=0.txt",
}


SWEEP_N = 10500
"""Samples of the "p_sweep" run (21 s)."""

SWEEP_FROM_S, SWEEP_S, SWEEP_AMPLITUDE, SWEEP_KP = 0.5, 20.0, 50.0, 1.0
"""The "p_sweep" run: its reference 50 sin(2 pi (t - 0.5)^2), 0-40 Hz from 0.5 s for 20 s,
under P control kp = 1 (the rig's 2014 sweep ``without_accel_01_28_14_test_2``)."""

RAMP_RATE = 0.05
"""DAC counts per sample of the "open_loop_ramp" reference (0 to 50 in 2 s)."""


def reference(run: str, n: int = N) -> np.ndarray:
    """u[k] of a run, shape (n,): encoder counts (DAC counts in open loop).

    Besides the :data:`RUNS` of a case, "open_loop_ramp" (v = :data:`RAMP_RATE` * k, truncated
    by the PC to whole counts: one more count every 20 samples) finds a still motor's
    breakaway level; it is not a rig run and not part of a case.
    """
    u = np.zeros(n)
    if run == "p_step":
        u[50:] = 50.0
    elif run == "lead_step":
        u[10:] = 100.0
    elif run == "lead_accel_step":
        u[10:] = 200.0
    elif run == "open_loop_pulses":
        u[20:70] = 100.0
        u[700:750] = -100.0
    elif run == "open_loop_ramp":
        u[:] = RAMP_RATE * np.arange(n)
    elif run == "p_sweep":
        t = np.arange(n) * DT - SWEEP_FROM_S
        u[:] = np.where((t >= 0) & (t < SWEEP_S), SWEEP_AMPLITUDE * np.sin(2 * np.pi * t ** 2), 0.0)
    else:
        raise ValueError(f"unknown run {run!r}; expected one of {RUNS}")
    return u


def _coeffs(x: np.ndarray) -> str:
    with np.printoptions(precision=8, floatmode="maxprec", suppress=False):
        return np.array_str(np.asarray(x, float))


def header(run: str) -> list[str]:
    """The rig's header lines of a run (without newlines), the column line last."""
    if run == "p_step":
        return ["#SLFR RTP P_control_Test", "#kp=2.0", COLUMNS]
    if run == "p_sweep":
        return ["#SLFR RTP P_control_Test", f"#kp={SWEEP_KP:.1f}", COLUMNS]
    if run == "open_loop_pulses":
        return ["#SLFR RTP OL_Test", COLUMNS]
    num, den = gth_design()
    lines = ["#SLFR RTP Motor_Comp_w_accel_fb", f"#Gth num={_coeffs(num)}", f"#Gth den={_coeffs(den)}"]
    if run == "lead_accel_step":
        gnum, gden = ga_design()
        lines += [f"#Ga num={_coeffs(gnum)}", f"#Ga den={_coeffs(gden)}"]
    else:
        lines += ["#Ga num=[]", "#Ga den=[]"]
    return lines + [COLUMNS_ACCEL]


def _num(x: float) -> str:
    return f"{x:.10g}"


def format_run(run: str, sim: Run) -> str:
    """The whole log text of a simulated run."""
    accel = run in ("lead_step", "lead_accel_step")
    lines = list(header(run))
    for k in range(len(sim.u)):
        row = [k * DT, k, sim.u[k], sim.v[k], sim.theta[k], sim.a[k]] + ([sim.theta_d_hat[k]] if accel else [])
        lines.append("\t".join(_num(float(x)) for x in row))
    return "\n".join(lines) + "\n"


KIND = {"p_step": "p", "lead_step": "lead", "lead_accel_step": "lead-accel", "open_loop_pulses": "open-loop",
        "open_loop_ramp": "open-loop", "p_sweep": "p"}
"""Controller kind of each run (see :func:`tests.blind.rig.simulate`)."""


def simulate_case(effects: dict[str, float], seed: int, n_elements: int = 4, substeps: int = 100,
                  accel_noise: float = 0.3, alignment: int = 1) -> dict[str, Run]:
    """The four runs of a case, simulated (see :func:`write_case`)."""
    rngs = np.random.default_rng(seed).spawn(len(RUNS))
    return {run: simulate(KIND[run], reference(run), dict(effects), rng, n_elements=n_elements,
                          substeps=substeps, accel_noise=accel_noise, alignment=alignment)
            for run, rng in zip(RUNS, rngs)}


def write_case(folder: Path, effects: dict[str, float], seed: int, n_elements: int = 4,
               substeps: int = 100, accel_noise: float = 0.3, alignment: int = 1) -> list[Path]:
    """Write the four 2 s rig-format logs of one blind test case.

    Parameters
    ----------
    folder : Path
        Created if missing; the files are named like the rig's (:data:`FILES`).
    effects : dict
        Hidden effects, DESIGN.md "Model diagnosis contract" names and units, e.g.
        ``{"coulomb_friction": 8.0, "param:drive_c": 1.6}``; ``{}`` for the nominal plant;
        also "stribeck_speed" (rad/s, static_friction's) and the out-of-vocabulary effects of
        :data:`tests.blind.rig.OOV`.
    seed : int
        Seed of the accelerometer noise.
    n_elements : int
        Beam elements of the generator's FEM.
    substeps : int
        Integration sub-steps per sample for friction, backlash and cogging.
    accel_noise : float
        Accelerometer noise std, counts.
    alignment : {1, 0}
        The closed loops' alignment (:func:`tests.blind.rig.simulate`): 1 as the rig's later
        logs and protocol v1, 0 as its 2009 logs.

    Returns
    -------
    list of Path
        In the order of :data:`RUNS`: P step, lead step, lead + accelerometer step,
        open-loop pulses.

    Raises
    ------
    ValueError
        An unknown effect name, static_friction below coulomb_friction.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    sims = simulate_case(effects, seed, n_elements, substeps, accel_noise, alignment)
    paths = []
    for run in RUNS:
        path = folder / FILES[run]
        path.write_text(format_run(run, sims[run]))
        paths.append(path)
    return paths


SWEEP_FILE = "swept_sine_amp_50_SLFR_RTP_P_control_kp=1.0.txt"
"""The file name of :func:`write_sweep`'s run."""


def write_sweep(folder: Path, effects: dict[str, float], seed: int, n_elements: int = 4, substeps: int = 100,
                accel_noise: float = 0.3) -> Path:
    """Write the "p_sweep" run (module docstring) beside a case's four, in the rig's log format.

    Parameters
    ----------
    folder : Path
        Created if missing; the file is :data:`SWEEP_FILE`.
    effects : dict
        As :func:`write_case`'s, and the accelerometer's configuration
        (:data:`tests.blind.rig.CONFIGURATIONS`: ``{"accel_mounted": 0.0}`` off the beam).
    seed : int
        Seed of the accelerometer noise (another stream than the case's runs').
    n_elements, substeps, accel_noise
        As :func:`write_case`'s.

    Returns
    -------
    Path
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng([seed, len(RUNS)])
    sim = simulate(KIND["p_sweep"], reference("p_sweep", SWEEP_N), dict(effects), rng, n_elements=n_elements,
                   substeps=substeps, accel_noise=accel_noise, kp=SWEEP_KP)
    path = folder / SWEEP_FILE
    path.write_text(format_run("p_sweep", sim))
    return path
