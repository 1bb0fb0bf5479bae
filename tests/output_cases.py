"""Every command's output options as one table, and the inputs they are tried against
(issue 15, class 1; used by tests/test_outputs.py).

A command that writes files is one line of :data:`COMMANDS`: its arguments (with the
inputs as ``{step}``, ``{step2}``, ``{sweep}``, ``{model}``, ``{in}``), its file options, its
folder options with the files it writes in them, and which inputs it reads. A command that
writes nothing is listed with None, so that a new command cannot be forgotten.

The logs are written by a toy plant of this module (a motor with viscous friction, P
control with one sample of computational delay, the rig's header and columns), not by
``station.plant``: the commands read them as they would read the rig's.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

RIG_P_HEADER = "#SLFR RTP P_control_Test\n#kp={kp:.1f}\n#t\tn\tu\tv\t$\\theta$\ta\n"


def write_p_log(path: Path, u: np.ndarray, kp: float = 2.0, seed: int = 0) -> Path:
    """A rig-format P-control run: v[k] = sat(kp (u[k] - θ[k-1])), a toy motor θ, and an a that
    reads its acceleration (a channel of noise alone is no tip acceleration to the log audit)."""
    rng = np.random.default_rng(seed)
    n = u.size
    theta, v, a = np.zeros(n), np.zeros(n), rng.normal(0.0, 0.4, n)
    w, x = 0.0, 0.0
    for k in range(n):
        v[k] = np.trunc(np.clip(kp * (u[k] - (theta[k - 1] if k else 0.0)), -200, 200))
        a[k] += 40.0 * (0.004 * v[k] - 0.03 * w)  # the toy motor's change of speed
        w = 0.97 * w + 0.004 * v[k]
        x += w
        theta[k] = np.round(x)
    a = np.round(a)
    t = np.arange(n) * 0.002
    with open(path, "w") as fh:
        fh.write(RIG_P_HEADER.format(kp=kp))
        np.savetxt(fh, np.column_stack([t, np.arange(n), u, v, theta, a]),
                   fmt=["%.3f", "%d", "%g", "%g", "%g", "%g"], delimiter="\t")
    return path


def make_inputs(folder: Path) -> dict[str, Path]:
    """The inputs of the table in ``folder/in``: two step runs, a swept sine, a model file."""
    d = folder / "in"
    d.mkdir(parents=True, exist_ok=True)
    step = np.where(np.arange(300) >= 10, 50.0, 0.0)
    t = np.arange(2100) * 0.002
    sweep = np.where(t > 1.0, np.trunc(50 * np.sin(2 * np.pi * (t - 1.0) ** 2)), 0.0)
    model = d / "model.toml"
    model.write_text('name = "table-model"\nparams = "tmm-fit"\nn_elements = 2\n')
    return {"step": write_p_log(d / "step.txt", step), "step2": write_p_log(d / "step2.txt", step * 1.5, seed=1),
            "sweep": write_p_log(d / "sweep.txt", sweep, kp=1.0, seed=2), "model": model, "in": d}


@dataclass(frozen=True)
class Command:
    """One command of the table (see the module's docstring)."""

    args: tuple[str, ...]
    files: tuple[str, ...]
    inputs: tuple[str, ...]
    folders: dict[str, tuple[str, ...]] = field(default_factory=dict)
    figure_of: str | None = None   # the file option whose <stem>.png is drawn beside it
    together: bool = True          # all its outputs are written at the end, whole or none
    command: str | None = None     # the subcommand, when the table's name is a mode of it

    def argv(self, name: str, inputs: dict[str, Path]) -> list[str]:
        return [self.command or name] + [a.format(**{k: str(v) for k, v in inputs.items()}) for a in self.args]


COMMANDS: dict[str, Command | None] = {
    "step": Command(("--duration", "0.1", "--quiet", "--reference", "{step}", "--model", "{model}"),
                    files=("--out", "--json", "--rrd"), inputs=("step", "model"), figure_of="--out", together=False),
    "replay": Command(("{step}", "--model", "{model}"), files=("--json", "--rrd"), inputs=("step", "model")),
    "compare": Command(("{step}", "--model", "{model}"), files=("--json",), inputs=("step", "model"),
                       folders={"--out-dir": ("step_compare.png",)}),
    "bode": Command(("{sweep}", "--nperseg", "1024", "--model", "{model}"), files=("--png", "--json"),
                    inputs=("sweep", "model")),
    "diagnose": Command(("{step}", "{step2}", "--model", "{model}", "--quiet"), files=("--json", "--save-model"),
                        inputs=("step", "step2", "model"),
                        folders={"--report": ("report.html", "step_run.png", "step_resid.png", "step2_run.png",
                                              "step2_resid.png")}),
    "survey": Command(("{in}", "--no-model", "--jobs", "1"), files=("--csv",), inputs=("model", "step", "step2", "sweep"),
                      folders={"--report": ("001_step.json", "002_step2.json", "003_sweep.json", "survey.txt")}),
    "survey --diagnose": Command(("--diagnose", "{in}", "--model", "{model}"), files=("--json",),
                                 inputs=("model", "step", "step2", "sweep"), command="survey",
                                 folders={"--save-models": ("in.toml",), "--report": ("report.html", "drift.png")}),
    "plot": Command(("{step}",), files=("--out",), inputs=("step",)),
    "modes": Command(("--elements", "1", "2", "--model", "{model}"), files=("--json",), inputs=("model",)),
    "identify": Command(("--budget", "0", "--model", "{model}", "--out-dir", "runs/identify", "--quiet"),
                        # not --save-model: diagnose's case covers the option's writing
                        files=("--json",), inputs=("model",),
                        folders={"--report": ("identify.html", "report.html")}, together=False),
    "tune": Command(("--controller", "lead", "--samples", "0", "--shaper", "none", "--jobs", "1", "--model", "{model}",
                     "--quiet"), files=("--out", "--json"), inputs=("model",),
                    folders={"--report": ("report.html", "steps.png", "bode.png", "robust.png", "verify-step.tsv")}),
    "sim-device": None,  # serves a pty; its summary goes to stdout
    "ports": None,
}
"""Command name -> its outputs (None: it writes no file)."""

SUFFIX = {"--out": ".tsv", "--json": ".json", "--rrd": ".rrd", "--png": ".png", "--save-model": ".toml",
          "--csv": ".csv"}
"""A natural suffix per file option (step's --out must not end in .png: its figure would be the log)."""


def default_outputs(name: str, cmd: Command, root: Path) -> dict[str, Path]:
    """A fresh path per option under ``root/out`` (folders: a folder per option)."""
    out = {opt: root / "out" / f"{name}{opt.strip('-').replace('-', '_')}{SUFFIX.get(opt, '')}" for opt in cmd.files}
    out.update({opt: root / "out" / f"{name}_{opt.strip('-').replace('-', '_')}" for opt in cmd.folders})
    return out


def targets(cmd: Command, chosen: dict[str, Path]) -> dict[str, list[Path]]:
    """Every file each chosen option makes the command write (derived files included)."""
    got = {}
    for opt, path in chosen.items():
        if opt in cmd.folders:
            got[opt] = [path / f for f in cmd.folders[opt]]
        elif opt == cmd.figure_of:
            got[opt] = [path, path.with_suffix(".png")]
        else:
            got[opt] = [path]
    return got


def snapshot(root: Path) -> dict[str, str]:
    """Every file under ``root`` (hidden ones too) -> its content's hash."""
    return {str(p.relative_to(root)): hashlib.sha1(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


def parts(root: Path) -> list[Path]:
    """Temporary files a failed write would have left (station.outputs names them .NAME.XXXX.part)."""
    return [p for p in root.rglob("*.part")]


def run_on_file_systems(root: Path, full: Path, ro: Path) -> list[dict]:
    """Every file and folder option of every command set to a real full file system (``full``,
    filled up first) and to a real read-only one (``ro``), run in this process; one record per
    case: command, option, where, exit code, stderr, the files left in ``full``."""
    import contextlib
    import io

    import station.diagnosis.search.workbench as workbench
    from station.cli import main

    workbench.CANDIDATES = ("coulomb_friction",)  # the writing is tested, not the search (diagnose and sessions)
    with open(full / "filler", "wb", buffering=0) as fh:  # take every page of the tmpfs
        try:
            while fh.write(b"\0" * 4096):
                pass
        except OSError:
            pass
    inputs = make_inputs(root)
    os.chdir(root)
    cases = [(name, cmd.argv(name, inputs), option, where, folder / default_outputs(name, cmd, root)[option].name)
             for name, cmd in COMMANDS.items() if cmd is not None
             for option in list(cmd.files) + list(cmd.folders) for where, folder in (("full", full), ("ro", ro))]
    # without --duration, step does not estimate the log's size: its writer meets the full disk
    cases.append(("step", ["step", "--quiet"], "--out", "full", full / "default.tsv"))
    records = []
    for name, argv, option, where, target in cases:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            code = main(argv + [option, str(target), "--force"])
        records.append({"command": name, "option": option, "where": where, "code": code, "stderr": err.getvalue(),
                        "left": sorted(str(p.relative_to(full)) for p in full.rglob("*") if p.name != "filler")})
    return records


if __name__ == "__main__":  # python -m tests.output_cases ROOT FULL RO (in a mount namespace: test_outputs_os.py)
    import json
    import sys

    print(json.dumps(run_on_file_systems(*map(Path, sys.argv[1:4]))))
