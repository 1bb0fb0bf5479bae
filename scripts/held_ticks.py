#!/usr/bin/env python3
"""What held ticks do to a step response: the basis of the held-tick budget (docs/safety.md).

A tick on a held command is one the station did not answer in time: the device kept its
last output (v1 reports it LATE), or the station caught up and skipped the sample (its
controller not stepped). This simulates the thesis's three step tests on a model (default
the built-in ``rig``) with a fraction of the ticks held at random — the command stays, the
controller is not stepped — and prints the overshoot and 2 % settling time against the
fraction, the mean and spread over seeds. It says how many held ticks per 100 a run can
have and still measure what it was run to measure.

Usage: ``python scripts/held_ticks.py [--model rig] [--fractions 0 0.1 0.2 0.3 0.5] [--seeds 5]``.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from station.rig import DT
from station.analysis.metrics import step_metrics
from station.control import step_reference
from station.plant.model import as_model
from station.plant.simulate import simulate
from station.ranges import number
from station.runsetup import choose_controller

STEPS = (("p", 50), ("lead", 100), ("lead-accel", 200))  # the thesis's step tests (controller, counts)


class HeldTicks:
    """A controller whose command is held on a random fraction of the ticks (not stepped then).

    Parameters
    ----------
    controller : controller object
        ``step(u, theta, a) -> (v, theta_d_hat)``, ``reset()``, ``spec``.
    fraction : float
        Probability that a tick is held, 0..1.
    seed : int
        Seed of the held ticks' draw.
    """

    def __init__(self, controller, fraction: float, seed: int):
        self.controller, self.fraction, self.seed = controller, fraction, seed
        self.spec, self.limit = controller.spec, getattr(controller, "limit", None)
        self.reset()

    def reset(self) -> None:
        """Both at rest, and the draw restarted."""
        self.controller.reset()
        self.rng = np.random.default_rng(self.seed)
        self.held = (0.0, 0.0)

    def step(self, u: float, theta: float, a: float) -> tuple[float, float]:
        """The controller's output, or on a held tick the last one.

        Parameters
        ----------
        u, theta, a : float
            Reference and samples (as the controller's ``step``).
        """
        if self.rng.random() >= self.fraction:
            self.held = self.controller.step(u, theta, a)
        return self.held


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="rig", help="built-in model name or model file (default rig)")
    ap.add_argument("--fractions", type=number(0.0, 0.9), nargs="+", default=[0.0, 0.1, 0.2, 0.3, 0.5],
                    help="fractions of the ticks held (default 0 0.1 0.2 0.3 0.5)")
    ap.add_argument("--seeds", type=number(1, 1000, integer=True), default=5, help="seeds per fraction (default 5)")
    args = ap.parse_args(argv)
    model = as_model(args.model)
    n = 1000  # 2 s, as station step
    t = np.arange(n) * DT
    print(f"model {model.name}: step tests with a fraction of the ticks held at random, mean (spread) over "
          f"{args.seeds} seeds")
    for name, amplitude in STEPS:
        u = step_reference(amplitude, n)
        for fraction in args.fractions:
            over, settle = [], []
            for seed in range(args.seeds):
                chosen = choose_controller(name).controller
                m = step_metrics(t, simulate(model, HeldTicks(chosen, fraction, seed), u).theta, amplitude)
                over.append(m.overshoot_pct)
                settle.append(np.nan if m.settling_time_s is None else m.settling_time_s)
            settled = [s for s in settle if np.isfinite(s)]
            st = f"{np.mean(settled):.3f} s" if settled else "not settled"
            print(f"  {name:10} step {amplitude:3d}, {fraction:4.0%} held: overshoot {np.mean(over):5.1f} % "
                  f"({np.ptp(over):.1f}), settling {st} ({len(settled)} of {args.seeds} settled)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
