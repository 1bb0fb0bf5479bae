"""A tuned compensator proved before it leaves: run as a real ``station step`` on the simulated rig.

The compensator file is run by :func:`station.experiment.run_step` exactly as ``station step
--controller FILE`` runs it (the file read back, Tustin at the sample time, the loop, protocol
v1, the log), on the simulated rig serving the design model (``sim://?noise=0``: without the
accelerometer's noise the run is deterministic), and the logged run is compared with the
design's own simulation (:func:`station.design.evaluate.step_run`): θ, a and v must agree
sample for sample, and the log's step figures are the design's.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import NamedTuple

import numpy as np

from station.control.designs import read_compensator_file
from station.design.evaluate import RUN_S, step_figures, step_run
from station.experiment import run_step
from station.rig import DEFAULT_STEP_TICK
from station.runlog import read_log


class Verification(NamedTuple):
    """The step on the simulated rig against the design's simulation.

    Attributes
    ----------
    log : Path or None
        The run's log (None when it was written to a temporary folder, now gone).
    reason : str
        The run's outcome ("completed" when it ran to the end).
    max_abs_dtheta, max_abs_da, max_abs_dv : float
        Largest |logged − simulated| of θ (encoder counts), a (accelerometer counts) and v
        (DAC counts).
    overshoot_pct : float
        The logged step's overshoot, %.
    settling_2pct_s : float or None
        The logged step's 2 % settling time, s.
    tip_residual_rms : float
        The logged accelerometer's RMS from 0.6 s after the step to the run's end, counts.
    """

    log: Path | None
    reason: str
    max_abs_dtheta: float
    max_abs_da: float
    max_abs_dv: float
    overshoot_pct: float
    settling_2pct_s: float | None
    tip_residual_rms: float = float("nan")

    @property
    def matches(self) -> bool:
        """The run completed and the log equals the simulation sample for sample."""
        return self.reason == "completed" and self.max_abs_dtheta == 0 and self.max_abs_dv == 0 \
            and self.max_abs_da == 0

    def to_json(self) -> dict:
        """The fields and ``matches``.

        Returns
        -------
        dict
            Every field by name (``log`` as a string or None; units as the attributes) and
            ``matches`` (bool).
        """
        return {"log": None if self.log is None else str(self.log), "reason": self.reason,
                "max_abs_dtheta": self.max_abs_dtheta, "max_abs_da": self.max_abs_da,
                "max_abs_dv": self.max_abs_dv, "overshoot_pct": self.overshoot_pct,
                "settling_2pct_s": self.settling_2pct_s, "tip_residual_rms": self.tip_residual_rms,
                "matches": self.matches}


def verify(model, compensator_file: str | Path, amplitude: float, log: str | Path | None = None,
           run_s: float = RUN_S) -> Verification:
    """Run a compensator file as ``station step`` on the simulated rig serving ``model`` and
    compare the log with the simulation.

    Parameters
    ----------
    model : station.plant.model.Model
        The model the simulated rig serves.
    compensator_file : str or Path
        The written compensator file.
    amplitude : float
        Step height, encoder counts.
    log : str or Path, optional
        Where to keep the run's log (overwritten); default: a temporary folder, removed.
    run_s : float
        The run's length, s.

    Returns
    -------
    Verification
        The run's outcome, the largest logged-minus-simulated differences of θ, a and v over
        their common length, and the logged step's overshoot, 2 % settling time and tip residual.

    Raises
    ------
    StationError
        The file cannot be read, or the run cannot start.
    """
    with tempfile.TemporaryDirectory(prefix="station-tune-") as tmp:
        path = Path(log) if log is not None else Path(tmp) / "verify-step.tsv"
        report = run_step(port="sim://?noise=0", controller=str(compensator_file), amplitude=amplitude,
                          duration=run_s, step_tick=DEFAULT_STEP_TICK, model=model, out=path, force=True,
                          figure=False, progress=False)
        data = read_log(path).data
        sim = step_run(model, read_compensator_file(compensator_file).compensator(), amplitude, run_s)
        n = min(data["theta"].size, sim.theta.size)

        def dmax(key):
            return float(np.max(np.abs(data[key][:n] - sim[key][:n]))) if n else float("nan")

        figs = step_figures(data, amplitude, None)
        return Verification(None if log is None else path, report.result.reason, dmax("theta"), dmax("a"),
                            dmax("v"), float(figs[0]), figs[1], figs[12])
