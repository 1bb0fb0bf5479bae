"""Where and why a rig model misses the rig's swept sines (docs/diagnosis.md "Which model to
ship"): each sweep simulated as the rig ran it (:meth:`station.logged.LoggedRun.simulate`,
closed loop with the log's controller, reference, alignment and quantization — what
``station compare`` does) on tmm-fit and on the models given, and its θ error taken apart.

    python scripts/rig_sweeps.py                              # the two unseen 2013-14 sweeps, tmm-fit vs rig
    python scripts/rig_sweeps.py --model rig --model old.toml --figure docs/figures/rig_unseen_sweeps.png --force

Prints, per log and model: θ RMS and its gain over tmm-fit; the constant part of the error
(its mean) and its share of the mean square; the error per stretch of the sweep (time, the
reference's frequency there, the share of the squared error); the plant's θ/v per frequency
band against the rig's (|G_model|/|G_rig| and the phase error, from the sweep's own spectra:
G = Θ(f)/V(f) of the logged and of the simulated v and θ); the θ/v antiresonance (the notch of
|G| between 2 and 4 Hz in 0.05 Hz bins) against the model's hub-held first mode
(:func:`station.plant.modes.modal_summary`), with and without the accelerometer's mass, and
the rig's hub-held ping (the hold-and-release log, :func:`station.analysis.beam.analyze_beam_test`);
and, on the four thesis logs, how far the hub moves in the 40 ms after the first command.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np
import scipy.signal
from matplotlib.figure import Figure

from station.analysis.beam import analyze_beam_test
from station.diagnosis.runs.cases import RunCase, load_case
from station.logged import LoggedRun
from station.plant.model import load_model
from station.plant.modes import modal_summary
from station.outputs import FORCE_HELP, Transaction, check_outputs

RIG = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "rig"
SWEEPS = ["swept_sine_kp_1_amp_50.txt", "without_accel_01_28_14_test_2.txt"]
PING = "log_dec_hold_and_release_1_SLFR_RTP_OL_Test_uend=77.txt"
THESIS = ["OL_pulse_test_sys_check_SLFR_RTP_OL_Test_uend=0.txt",
          "SFLR_P_control_step_kp_2_SLFR_RTP_P_control_kp=2.0.txt",
          "step_response_Gth_comp_no_accel_FB_amp_100_duration_1000_SLFR_RTP_Motor_Comp_Gth.txt",
          "step_response_Gth_comp_Ga_opt_amp_200_duration_1000_opt_case43_SLFR_RTP_Motor_Comp_Gth.txt"]
STRETCHES_S = (0.0, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 6.0, 10.0, 16.0, 22.0)
BANDS_HZ = ((0.3, 1.0), (1.0, 2.0), (2.0, 2.3), (2.3, 2.7), (2.7, 3.5), (3.5, 6.0), (6.0, 12.0), (12.0, 25.0))
NOTCH_HZ = (2.0, 4.0)


@dataclasses.dataclass
class Sim:
    """One log simulated on one model."""

    name: str
    theta: np.ndarray
    v: np.ndarray

    def error(self, case: RunCase) -> np.ndarray:
        return case.theta - self.theta


def simulate(case: RunCase, model) -> Sim:
    pred = case.run.simulate(model).prediction
    return Sim(model.name, np.asarray(pred["theta"], float), np.asarray(pred["v"], float))


def reference_hz(u: np.ndarray, dt: float) -> np.ndarray:
    """The reference's instantaneous frequency, Hz (the phase of its analytic signal); 0 where it is 0."""
    phase = np.unwrap(np.angle(scipy.signal.hilbert(u)))
    f = np.gradient(phase, dt) / (2 * np.pi)
    return np.where(u != 0, f, 0.0)


def frf(v: np.ndarray, theta: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frequencies (Hz), |V|² and G = Θ/V of a whole sweep."""
    V = np.fft.rfft(v)
    with np.errstate(all="ignore"):
        return np.fft.rfftfreq(v.size, dt), np.abs(V) ** 2, np.fft.rfft(theta) / V


def band_ratio(f, w, g_model, g_rig, lo: float, hi: float) -> tuple[float, float]:
    """|G_model|/|G_rig| (power-weighted by the rig's |V|²) and the phase error, degrees."""
    m = (f >= lo) & (f < hi) & np.isfinite(g_model) & np.isfinite(g_rig)
    ratio = math.sqrt(np.sum(w[m] * np.abs(g_model[m]) ** 2) / np.sum(w[m] * np.abs(g_rig[m]) ** 2))
    phase = float(np.angle(np.sum(w[m] * g_model[m] * np.conj(g_rig[m])), deg=True))
    return ratio, phase


def notch_hz(f, w, g, lo: float = NOTCH_HZ[0], hi: float = NOTCH_HZ[1], width: float = 0.05) -> float:
    """The frequency of the smallest |G| (power-weighted over ``width`` Hz bins) in [lo, hi)."""
    edges = np.arange(lo, hi, width)
    mags = []
    for a in edges:
        m = (f >= a) & (f < a + width) & np.isfinite(g)
        mags.append(math.sqrt(np.sum(w[m] * np.abs(g[m]) ** 2) / np.sum(w[m])) if m.any() else math.inf)
    return float(edges[int(np.argmin(mags))] + width / 2)


def first_modes(model) -> str:
    """The model's hub-held first mode (the θ/v antiresonance), with and without the accelerometer."""
    p = model.linear_params()
    with_acc = modal_summary(p, model.n_elements)
    without = modal_summary(dataclasses.replace(p, m_accel=0.0, J_accel=0.0), model.n_elements)
    return (f"hub-held first mode {with_acc.antiresonances_hz[0]:.3f} Hz (ζ {with_acc.antiresonance_damping[0]:.4f}),"
            f" without the accelerometer's mass {without.antiresonances_hz[0]:.3f} Hz")


def explain(case: RunCase, sims: list[Sim], out=print) -> None:
    """The θ error of each model on one sweep, taken apart (module docstring)."""
    dt = case.run.dt
    t = np.arange(case.n) * dt
    u = np.asarray(case.run.data["u"], float)
    f_ref = reference_hz(u, dt)
    nominal = sims[0]
    out(f"\n== {case.name} ({case.n} samples, {case.kind}, alignment {case.alignment})")
    for s in sims:
        e = s.error(case)
        rms, mean = math.sqrt(float(np.mean(e ** 2))), float(np.mean(e))
        gain = 100 * (1 - rms / math.sqrt(float(np.mean(nominal.error(case) ** 2))))
        out(f"  {s.name:10s} θ RMS {rms:5.2f} counts (gain {gain:5.1f} %); mean error {mean:+.2f} counts"
            f" = {100 * mean ** 2 / rms ** 2:4.1f} % of the mean square")
    out("  stretch       ref. Hz  |θ| RMS  " + "  ".join(f"{s.name:>10s} RMS share" for s in sims))
    totals = [float(np.sum(s.error(case) ** 2)) for s in sims]
    for a, b in zip(STRETCHES_S[:-1], STRETCHES_S[1:]):
        m = (t >= a) & (t < b)
        if not m.any():
            continue
        active = m & (u != 0)
        f_med = float(np.median(f_ref[active])) if active.any() else 0.0
        row = f"  {a:4.1f}-{b:4.1f} s  {f_med:6.1f}  {math.sqrt(np.mean(case.theta[m] ** 2)):7.2f}  "
        row += "  ".join(f"{math.sqrt(np.mean(s.error(case)[m] ** 2)):10.2f} {100 * np.sum(s.error(case)[m] ** 2) / tot:4.0f} %"
                         for s, tot in zip(sims, totals))
        out(row)
    f, w, g_rig = frf(np.asarray(case.run.data["v"], float), case.theta, dt)
    gs = [frf(s.v, s.theta, dt)[2] for s in sims]
    out("  θ/v band, Hz   |G| rig  " + "  ".join(f"{s.name:>10s} |G|/rig phase°" for s in sims))
    for lo, hi in BANDS_HZ:
        m = (f >= lo) & (f < hi)
        g = math.sqrt(np.sum(w[m] * np.abs(g_rig[m]) ** 2) / np.sum(w[m]))
        out(f"  {lo:5.1f}-{hi:4.1f}     {g:7.3f}  " + "  ".join(
            "{:>15.2f} {:+6.1f}".format(*band_ratio(f, w, gm, g_rig, lo, hi)) for gm in gs))
    out(f"  θ/v notch ({NOTCH_HZ[0]:g}-{NOTCH_HZ[1]:g} Hz): rig {notch_hz(f, w, g_rig):.3f} Hz; "
        + ", ".join(f"{s.name} {notch_hz(f, w, gm):.3f} Hz" for s, gm in zip(sims, gs)))


def figure(cases: list[RunCase], sims: list[list[Sim]], path: str, tx: Transaction) -> None:
    """θ measured against each model where the sweeps cross the first mode, and the θ error's
    RMS per 0.25 s over the whole log."""
    fig = Figure(figsize=(12, 3.4 * len(cases)), layout="constrained")
    axes = fig.subplots(len(cases), 2, squeeze=False)
    styles = ["tab:blue", "tab:orange", "tab:green", "tab:red"]
    for row, (case, ss) in enumerate(zip(cases, sims)):
        t = np.arange(case.n) * case.run.dt
        ax, ax_e = axes[row]
        m = (t >= 0.8) & (t < 4.0)
        ax.plot(t[m], case.theta[m], "k", lw=2, label="rig (measured)")
        ax.plot(t[m], np.asarray(case.run.data["u"], float)[m], ":", color="0.5", lw=1, label="reference u")
        for s, c in zip(ss, styles):
            ax.plot(t[m], s.theta[m], color=c, lw=1.2, label=s.name)
        ax.set(title=f"{case.name}: θ, 0.8-4 s", xlabel="t, s", ylabel="θ, encoder counts")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="lower left")
        k = int(round(0.25 / case.run.dt))
        n = case.n // k * k
        tt = t[:n].reshape(-1, k).mean(axis=1)
        for s, c in zip(ss, styles):
            e = s.error(case)[:n].reshape(-1, k)
            rms = math.sqrt(float(np.mean(s.error(case) ** 2)))
            ax_e.plot(tt, np.sqrt(np.mean(e ** 2, axis=1)), color=c, label=f"{s.name} (whole log {rms:.2f})")
        ax_e.set(title="θ error, RMS per 0.25 s", xlabel="t, s (the sweep's frequency rises with t)",
                 ylabel="counts")
        ax_e.grid(True, alpha=0.3)
        ax_e.legend(fontsize=8)
    with tx.open(path, "the figure") as fh:
        fig.savefig(fh, format="png", dpi=110)


def onsets(models, samples: int = 20, out=print) -> None:
    """How far the hub moves in the first ``samples`` samples after each thesis log's first
    command, on the rig and on each model: a linear motor moves twice as far for twice the command."""
    out(f"\nθ {samples} samples after the first command (counts): rig / " + " / ".join(m.name for m in models))
    for name in THESIS:
        path = RIG / name
        if not path.exists():
            continue
        case = load_case(path)
        v = np.asarray(case.run.data["v"], float)
        k = int(np.argmax(np.abs(v) > 0.5)) + samples
        sims = [simulate(case, m).theta[k] for m in models]
        out(f"  {name[:40]:40s} v {v[k - samples]:+5.0f}: {case.theta[k]:4.0f} / "
            + " / ".join(f"{x:4.0f}" for x in sims))


def ping(out=print) -> None:
    """The rig's hub-held first mode from the hold-and-release log."""
    path = RIG / PING
    if not path.exists():
        return
    run = LoggedRun.from_path(path)
    bt = analyze_beam_test(run.data["t"], run.data["a"], run.dt)
    if bt.f1_hz is not None:
        out(f"\nrig, hub held (hold-and-release ping): first mode {bt.f1_hz:.3f} Hz, ζ {bt.zeta1:.4f}")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("logs", nargs="*", help="sweep logs (default: the two unseen 2013-14 sweeps in ../shared)")
    p.add_argument("--model", action="append", metavar="MODEL",
                   help="a built-in model or model file compared with tmm-fit (repeatable; default rig)")
    p.add_argument("--figure", metavar="PNG", help="write θ and its error per model as a PNG")
    p.add_argument("--force", action="store_true", help=FORCE_HELP)
    args = p.parse_args(argv)
    paths = args.logs or [str(RIG / f) for f in SWEEPS]
    check_outputs([("--figure", args.figure)], [("LOG", f) for f in paths], force=args.force, parser=p)
    models = [load_model("tmm-fit")] + [load_model(m) for m in (args.model or ["rig"])]
    for m in models:
        effects = ", ".join(f"{k} = {v:.4g}" for k, v in m.effect_dict().items()) or "no effects"
        print(f"model {m.name}: {effects}; {first_modes(m)}")
    ping()
    onsets(models)
    cases, sims = [], []
    for path in paths:
        case = load_case(path)
        cases.append(case)
        sims.append([simulate(case, m) for m in models])
        explain(case, sims[-1])
    if args.figure:
        with Transaction() as tx:
            figure(cases, sims, args.figure, tx)
        print(f"figure: {args.figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
