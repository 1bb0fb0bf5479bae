"""A logged run understood: :class:`LoggedRun`, the one place that knows what a log was."""

from __future__ import annotations

import dataclasses
from functools import cached_property
from pathlib import Path

import numpy as np

from station.analysis.beam import HELD_MIN_V, HubHeld, hub_held
from station.analysis.metrics import StepMetrics, step_metrics
from station.control.rerun import AlignmentFit, detect_alignment, is_closed_loop
from station.errors import StationError
from station.logged.accelerometer import ON_THE_TIP, Mounting, decide_mounting, motion_ratio, silent_claims
from station.logged.audit import (ACCEL_CLAIM, Audit, AuditClaim, accel_claims, alignment_claim,
                                  file_kp_claims, reference_claims)
from station.logged.columns import Columns, check_columns
from station.logged.sensor_swap import check_sensor_swap
from station.logged.controller import ControllerId, describe_controller, identify_controller
from station.logged.sensor_evidence import REST_MIN_SAMPLES, sensor_evidence
from station.logged.sensors import (DOUBT_WORDS, NO_FAULTS, REFINED_BY_MODEL, SensorFaults, decide_faults, fault_text,
                                   holds_signs)
from station.logged.reference import Reference, classify_reference
from station.logged.simulate import ModelRun, compared_theta, simulate_log
from station.logged.spikes import with_spikes
from station.logged.start import Start, start_claims
from station.logged.units import TimeBase, time_base
from station.runlog.timebase import restart_rows, row_ticks, run_start
from station.runlog import SKIPPED, RunLog, read_log

REPRODUCED_TOLERANCE = 1e-6
"""max |v_replayed - v_logged| (DAC counts) under which a replay counts as reproducing the log."""

class LoggedRun:
    """A run log and what it was: which controller ran it, with which alignment, closed or
    open loop, at which sample time, on which reference, whether it held the hub.

    Each question is answered once, when first asked (the controller identification and
    the alignment search replay the whole log), from the definitions of DESIGN.md "Timing
    and log rows" and "Compensators". Every claim the log makes is checked against its
    data first (DESIGN.md "Log audit", :attr:`audit`), and where the data contradict it
    their answer is what this class gives: the columns' units and the sample time
    (:func:`station.logged.units.time_base`), which column holds what
    (:func:`station.logged.columns.check_columns`), the controller, whether it was closed
    loop and its alignment (:func:`station.logged.controller.identify_controller`).

    Parameters
    ----------
    log : RunLog
        A log read by :func:`station.runlog.read_log`.

    Attributes
    ----------
    log : RunLog
        The log as its data say it is: ``raw_log`` itself, or a copy with t in s, θ in
        encoder counts, signed counts and its columns in their places when the audit found
        them otherwise, and the fields the controller's audit set aside as corrupted put
        right (:meth:`station.analysis.glitches.Glitches.repaired`): what every number of the
        run reads (its metrics, its model's fit, a diagnosis), so none reads a field the
        audit said is not the run's.
    raw_log : RunLog
        The log as read.
    """

    def __init__(self, log: RunLog):
        self.raw_log = log
        self._time_base: TimeBase = time_base(log)
        self._columns: Columns = check_sensor_swap(check_columns(self._time_base.log, _skipped(self._time_base.log)))
        self._checked = self._columns.log  # what the controller's audit reads
        self._simulable = False

    @cached_property
    def log(self) -> RunLog:
        """The log as its data say it is (the class's ``log``)."""
        g = self.identified.corrupted
        if g is None:
            return self._checked
        u, theta, a, v = g.repaired(self._checked.data["v"])
        return dataclasses.replace(self._checked, data={**self._checked.data, "u": u, "theta": theta, "a": a, "v": v})

    @classmethod
    def from_path(cls, path: str | Path) -> LoggedRun:
        """Read a log (:func:`station.runlog.read_log`) and understand it.

        Parameters
        ----------
        path : str or Path
            A run log, ours or the rig's.

        Raises
        ------
        station.runlog.RunLogError
            The log cannot be read.
        """
        return cls(read_log(path))

    def __repr__(self) -> str:
        return f"LoggedRun({str(self._checked.path)!r})"

    def __len__(self) -> int:
        return len(self._checked)

    @property
    def data(self) -> dict[str, np.ndarray]:
        """The log's columns (:attr:`station.runlog.RunLog.data`), shape (N,) each."""
        return self.log.data

    @cached_property
    def dt(self) -> float:
        """The sample time, s (:attr:`station.runlog.RunLog.dt`)."""
        return self.log.dt

    # --- which controller ran, and how ------------------------------------------------
    @cached_property
    def identified(self) -> ControllerId:
        """Which controller ran the log, where that came from and its audit row; none for a log
        without rows (:func:`station.logged.controller.identify_controller`), with the corrupted
        fields of the columns its law does not read (:func:`station.logged.spikes.with_spikes`).

        Raises
        ------
        StationError
            Our header's controller spec is malformed, or a rig header's gain is not a number.
        """
        cid = self._columns.identified  # the column check identified it already, or None
        cid = cid or (identify_controller(self._checked, self.skipped) if len(self) else ControllerId(None, None, []))
        return with_spikes(self._checked, cid)

    @cached_property
    def audit(self) -> Audit:
        """Every claim of the log checked against its data (DESIGN.md "Log audit"):
        controller, alignment, reference, sample time, columns; and where the controller
        came from. ``audit.lines()`` are the contradictions, one line each, to say first.

        Raises
        ------
        StationError
            As :attr:`identified`, or the log lacks a column replaying its controller needs.
        """
        cid = self.identified
        claims = [] if cid.claim is None else [cid.claim]
        if len(self):
            spec = getattr(self.controller, "spec", None) or {}
            kp = spec.get("kp") if spec.get("kind") == "p" else None
            claims += file_kp_claims(self.log.path, describe_controller(self.controller), kp)
        if self.closed and self.replayed is not None and cid.judged_to != 0:  # 0: judged on no row
            row = alignment_claim(self.header_alignment, self.alignment, self.reproduced, self.log.format,
                                  cid.alignments)
            if row is not None:
                claims.append(row)
        claims += reference_claims(self.log, self.reference)
        claims += self.start.claims
        claims += self._time_base.claims
        claims += self._columns.claims
        claims += self._accel_claims
        if self.mounting.claim is not None:
            claims.append(self.mounting.claim)
        return Audit(tuple(claims) + self.sensors.claims, cid.source)

    def audit_for(self, model) -> Audit:
        """:attr:`audit` as said beside a model: where the model holds the sensors' signs and
        scales of its own (one a diagnosis saved, :meth:`found_faults`), a reversed
        accelerometer's claim says the gain the model simulates with, this run's own estimate
        beside it (:meth:`station.logged.sensors.SensorFaults.refined`), so a comparison never
        quotes one gain in its audit and simulates with another.

        Parameters
        ----------
        model : station.plant.model.Model or station.plant.DiscretePlant

        Returns
        -------
        Audit
        """
        if not holds_signs(model):
            return self.audit
        faults = self.sensors.refined(model.effect_dict(), by=REFINED_BY_MODEL)
        if faults is self.sensors:
            return self.audit
        audit = self.audit  # its claims end with this run's sensors' (above)
        return Audit(audit.claims[:len(audit.claims) - len(self.sensors.claims)] + faults.claims,
                     audit.controller_source)

    @cached_property
    def _accel_claims(self) -> list[AuditClaim]:
        if not len(self):
            return []
        dt, rest = self.log.dt, self.accel_rest_samples
        claims = accel_claims(self.data["a"], dt, self.accel_rest_offset, rest)
        if claims or self.held is not None:
            return claims
        return silent_claims(self.data["a"], dt, rest, self._nominal_a)

    def _nominal_a(self) -> tuple[np.ndarray, float] | None:
        """The nominal model's a for this run, driven open loop by the command the log applied,
        and how far the hub moved against the model's (:func:`station.logged.accelerometer.silent_claims`);
        None when the run cannot be simulated. The logged command, not the log's controller: a
        loop fed back from a biased or dead a moved the rig otherwise than the nominal loop would
        (blind, an unzeroed accelerometer's 114 counts through Ga's DC gain of 18 drifted the hub
        352 counts away from a step of 200: the nominal loop's a was 'expected' there)."""
        # lazy: start-up time (the FEM, only for a log whose a stays still)
        from station.plant.model import load_model

        if any(not self.has_column(n) for n in self.model_columns):
            return None
        try:
            sim = simulate_log(self.log, None, None, load_model("tmm-fit"))
        except (StationError, ArithmeticError, ValueError):  # a run the model cannot replay decides nothing here
            return None
        return sim.prediction["a"], motion_ratio(sim.theta_measured, sim.prediction["theta"], self.dt)

    @property
    def accel_is_tip(self) -> bool:
        """False when the data say the a column is no tip acceleration (a silent channel, a
        baseline that creeps with nothing in it): :attr:`station.logged.audit.Audit.accel_is_tip`
        before the rest of the audit is asked."""
        return not any(c.header == ACCEL_CLAIM for c in self._accel_claims)

    @cached_property
    def sensors(self) -> SensorFaults:
        """This run's sensors' and motor's signs and scales, decided from its own data against
        the nominal model driven by its applied command (:func:`station.logged.sensors.decide_faults`
        on this run alone, signs and scales, and a bias only far past what the rig's zeroing
        leaves: otherwise an accelerometer's bias or drift is decided over a session's runs, by a
        diagnosis). Its "columns" claims are in :attr:`audit`, and
        :meth:`simulate` uses its decided faults. :data:`station.logged.sensors.NO_FAULTS` for a
        run without rows, a hub-held beam test or one the nominal model cannot simulate."""
        if not len(self) or self.held is not None or any(not self.has_column(n) for n in self.model_columns):
            return NO_FAULTS
        # lazy: start-up time (the FEM, only when a log's claims are checked)
        from station.plant.model import load_model

        try:
            evidence = sensor_evidence(self, load_model("tmm-fit"))
        except (StationError, ArithmeticError, ValueError):  # a run the model cannot replay decides nothing here
            return NO_FAULTS
        return decide_faults([evidence], trends=False)

    @cached_property
    def mounting(self) -> Mounting:
        """Whether the accelerometer's mass was on the beam (:func:`station.logged.accelerometer.decide_mounting`),
        asked only when a reads no tip acceleration (one that reads is on the beam) or the log has
        no a column, and the hub was free."""
        if (self.accel_is_tip and self.has_column("a")) or not len(self) or self.held is not None:
            return ON_THE_TIP
        d = self.data
        applied = d["v_applied"]
        v = applied if applied.size and np.all(np.isfinite(applied)) else d["v"]
        return decide_mounting(v, d["theta"], self.dt)

    def model_for(self, model):
        """The model as this run had the rig: without the accelerometer's mass and rotary
        inertia (``accel_mounted`` 0) when the data say it was off the beam (:attr:`mounting`),
        else the model itself.

        Parameters
        ----------
        model : station.plant.model.Model or station.plant.DiscretePlant

        Returns
        -------
        station.plant.model.Model or station.plant.DiscretePlant
            ``model``, or a copy (a DiscretePlant's with its parameter set's m_accel and
            J_accel 0).
        """
        if self.mounting.mounted is not False:
            return model
        if hasattr(model, "with_effects"):
            return model.with_effects({"accel_mounted": 0.0})
        params = dataclasses.replace(model.params, m_accel=0.0, J_accel=0.0)
        return type(model)(params, n_elements=model.n_elements, dt=model.dt)

    @cached_property
    def start(self) -> Start:
        """How the run starts: at rest at t = 0 or moving (a copy cut from a longer run), and θ
        there (:func:`station.logged.start.start_claims`)."""
        d = self.data
        return start_claims(d["theta"], d["a"], d["u"], d["v"], self.dt, self.closed, self.accel_is_tip,
                            self.identified.cut, self.sensors.effects.get("accel_gain", 1.0),
                            self.sensors.effects.get("encoder_scale", 1.0))

    @property
    def audit_lines(self) -> list[str]:
        """The contradicted claims, one line each (``header: ...; data: ...``), to say before anything else."""
        return self.audit.lines()

    @property
    def controller(self):
        """The controller that ran the log (Compensator or OpenLoop), None when unknown."""
        return self.identified.controller

    @property
    def source(self) -> str | None:
        """Where the controller came from: "header", "inferred", "inferred (header
        contradicted)" or None (DESIGN.md's ``controller_source``)."""
        return self.identified.source

    @property
    def notes(self) -> list[str]:
        """What the identification assumed or could not do, one line each (a new list)."""
        return list(self.identified.notes)

    @property
    def closed(self) -> bool:
        """Whether the run was closed loop (:func:`station.control.rerun.is_closed_loop`)."""
        return is_closed_loop(self.controller)

    # --- what the log holds: the columns each use needs ------------------------------------

    def has_column(self, name: str) -> bool:
        """Whether the log holds the column ``name`` (the reader fills a column the log lacks
        with NaN; a log without rows lacks none).

        Parameters
        ----------
        name : str
            A standard column name (:data:`station.runlog.COLUMNS`).
        """
        col = self.data[name]
        return not col.size or bool(np.any(~np.isnan(col)))

    @property
    def replay_columns(self) -> tuple[str, ...]:
        """The columns replaying the log's controller needs: u and v; in closed loop also θ,
        and a when the controller has accelerometer feedback (() without a controller)."""
        c = self.controller
        if c is None:
            return ()
        if not self.closed:
            return ("u", "v")
        return ("u", "theta", "v") + (("a",) if getattr(c, "ga", None) is not None else ())

    @property
    def model_columns(self) -> tuple[str, ...]:
        """The columns simulating the run on a model needs: θ and a (the fit) and what drives
        the model: u in closed loop, else v (none when the log has v_applied)."""
        if self.closed:
            return ("u", "theta", "a")
        return (() if self.has_column("v_applied") else ("v",)) + ("theta", "a")

    @property
    def simulated_columns(self) -> tuple[str, ...]:
        """What simulating the run and fitting its θ need: :attr:`model_columns` but a (a
        log without it gets no a fit, and no sensor audit)."""
        return tuple(n for n in self.model_columns if n != "a")

    def check_columns(self, names, purpose: str) -> None:
        """Refuse a log that lacks a column a use needs: one line naming the log, the column
        and the use, instead of a result computed on NaN.

        Parameters
        ----------
        names : iterable of str
            The columns needed (e.g. :attr:`replay_columns`, :attr:`model_columns`).
        purpose : str
            The use, for the message (e.g. "simulating it on a model").

        Raises
        ------
        StationError
            ``PATH: no 'a' column: PURPOSE needs u, theta, a (columns found: ...)``; ``key``
            is the first missing column.
        """
        names = tuple(names)
        missing = [n for n in names if not self.has_column(n)]
        if missing:
            found = ", ".join(n for n in self.data if self.has_column(n)) or "none"
            raise StationError(f"{self.log.path}: no {', '.join(repr(m) for m in missing)} column: {purpose} "
                               f"needs {', '.join(names)} (columns found: {found})",
                               file=self.log.path, key=missing[0])

    @cached_property
    def replayed(self) -> AlignmentFit | None:
        """The controller run over the logged samples at its best alignment
        (:func:`station.control.rerun.detect_alignment`); None without a controller or rows.

        Raises
        ------
        StationError
            The log lacks a column the replay needs (:attr:`replay_columns`).
        """
        if self.controller is None or not len(self):
            return None
        self.check_columns(self.replay_columns, f"replaying its controller ({self.controller.name})")
        if self.identified.fit is not None:  # replayed when the audit checked it
            return self.identified.fit
        d = self.data
        return detect_alignment(self.controller, d["u"], d["theta"], d["a"], d["v"], skipped=self.skipped,
                                restarts=restart_rows(d["n"]))

    @cached_property
    def ticks(self) -> np.ndarray | None:
        """Each row's tick from the first row's when rows are missing or repeated, else None
        (:func:`station.runlog.timebase.row_ticks`)."""
        return row_ticks(self.data["n"])

    @property
    def skipped(self) -> np.ndarray | None:
        """Rows whose sample the station did not answer (our logs' :data:`station.runlog.SKIPPED`
        status bit; None for a log without a status column or without skips)."""
        return _skipped(self._checked)

    @property
    def alignment(self) -> int | None:
        """The computational delay d, samples, detected from the data; None unless closed
        loop (in open loop, v = u, d only decides whether v[0] is u[0] or 0)."""
        return self.replayed.alignment if self.closed and self.replayed is not None else None

    @property
    def max_abs_dv(self) -> float | None:
        """max |v_replayed - v_logged|, DAC counts (None when nothing was replayed)."""
        return None if self.replayed is None else self.replayed.max_abs_dv

    @property
    def reproduced(self) -> bool:
        """True when the replay reproduces the logged v within :data:`REPRODUCED_TOLERANCE`."""
        return self.max_abs_dv is not None and self.max_abs_dv <= REPRODUCED_TOLERANCE

    @property
    def header_alignment(self) -> int | None:
        """The alignment our log's header states (None: a rig log, or not stated)."""
        d = self.log.meta.get("alignment") if self.log.format == "station" else None
        return d if isinstance(d, int) and not isinstance(d, bool) else None

    # --- what the run was ----------------------------------------------------------------

    @cached_property
    def reference(self) -> Reference:
        """What the logged u is, told a closed loop's first θ (:func:`station.logged.reference.classify_reference`)."""
        return classify_reference(self.data["u"], float(self.data["theta"][0]) if len(self) and self.closed else None)

    @cached_property
    def held(self) -> HubHeld | None:
        """Why the run is a hub-held beam test (:func:`station.analysis.beam.hub_held`), None
        when it is not: then the logged v was not applied and the motor model cannot
        represent the run."""
        return hub_held(self.data["theta"], self.data["v"], self.dt) if len(self) else None

    @property
    def held_note(self) -> str:
        """One line on why the run is a hub-held beam test and what that rules out ("" when not)."""
        h = self.held
        if h is None:
            return ""
        return (f"hub-held beam test (theta within {h.theta_span:g} counts while |v| >= {HELD_MIN_V:g} for "
                f"{h.duration_s:.1f} s): the logged v was not applied, so the motor model cannot represent "
                f"this run and its fit is not computed")

    @property
    def theta(self) -> np.ndarray:
        """θ as a model is compared with it, encoder counts, shape (N,): relative to its
        first sample in open loop (:func:`station.logged.simulate.compared_theta`)."""
        return compared_theta(self.data["theta"], self.closed)

    @cached_property
    def accel_rest_samples(self) -> int:
        """Samples at rest at the start: before the first non-zero command, or before u, v or
        θ first leave their first row's values when the command is not 0 there (a loop
        holding an encoder that was not zeroed); all of them when nothing changes."""
        d = self.data
        v = np.asarray(d["v"], dtype=float)
        moving = np.flatnonzero(v != 0)
        if not moving.size or moving[0] > 0:
            return int(moving[0]) if moving.size else len(self)
        first = [int(np.flatnonzero(x != x[0])[0]) for x in (np.asarray(d[k], float) for k in ("u", "v", "theta"))
                 if x.size and np.all(np.isfinite(x)) and np.any(x != x[0])]
        return min(first, default=len(self))

    @cached_property
    def accel_rest_offset(self) -> float:
        """The accelerometer's mean before the first non-zero command, counts (0.0 with
        fewer than :data:`REST_MIN_SAMPLES` samples at rest)."""
        a = np.asarray(self.data["a"], dtype=float)
        rest = self.accel_rest_samples
        return float(np.mean(a[:rest])) if rest >= REST_MIN_SAMPLES else 0.0

    def step_metrics(self, theta=None, t=None) -> StepMetrics | None:
        """The thesis's step metrics of a closed-loop step run, against the step's
        classified amplitude (:attr:`reference`).

        Parameters
        ----------
        theta : array_like, shape (N,), optional
            The response, encoder counts (default: the logged θ; e.g. a simulation's).
        t : array_like, shape (N,), optional
            Its sample times, s (default: the logged t). Times are taken from the run's start:
            the first row's, whatever its clock read (a host's time stamps, 1-based ticks), or
            n[0] ticks before it where t and n agree on that (a copy cut from a longer run,
            :func:`station.runlog.timebase.run_start`).

        Returns
        -------
        StepMetrics or None
            None unless the run is closed loop on a step reference, logged from rest (a copy
            cut from a longer run does not hold the step's start).
        """
        if not (self.closed and self.reference.is_step and len(self)) or self.start.at_rest is False:
            return None  # a copy cut after the step: its overshoot is not the run's
        r, before = self.reference, run_start(self.data["t"], self.data["n"], self.dt)
        t = np.asarray(self.data["t"] if t is None else t, dtype=float)
        return step_metrics(t - t[0] + before, self.data["theta"] if theta is None else theta, r.amplitude, r.initial)

    def found_faults(self, model) -> dict[str, float]:
        """The sensor and wiring faults this run's data decided (:attr:`sensors`), for a model
        that holds no sign or scale of its own. The decision is one joint explanation against the
        nominal model (a reversed motor and encoder look like a reversed accelerometer), so a model
        that holds any of them (one a diagnosis saved carries its session's) gets none of it:
        never applied twice, never half of one explanation beside half of another.

        Parameters
        ----------
        model : station.plant.model.Model or station.plant.DiscretePlant

        Returns
        -------
        dict of str to float
            Effect -> value; empty for a DiscretePlant or a model that holds a sign or scale
            (:func:`station.logged.sensors.holds_signs`); less a bias or drift the model holds (its own stands).
        """
        if not hasattr(model, "effect_dict") or holds_signs(model):
            return {}
        return {k: v for k, v in self.sensors.effects.items() if k not in model.effect_dict()}

    def model_as_found(self, model, sensors: bool = True):
        """The model as the audit found this run's rig: :meth:`model_for` (the accelerometer's
        mass), with :meth:`found_faults` (the sensors' and motor's signs and scales) when ``sensors``.

        Parameters
        ----------
        model : station.plant.model.Model or station.plant.DiscretePlant
        sensors : bool, default True

        Returns
        -------
        station.plant.model.Model or station.plant.DiscretePlant
        """
        found = self.found_faults(model) if sensors else {}
        return self.model_for(model.with_effects(found) if found else model)

    def simulate(self, model, sensors: bool = True) -> ModelRun:
        """The run simulated on a model as the rig ran it (:func:`station.logged.simulate.simulate_log`
        with this run's controller and alignment, on :meth:`model_for`: without the
        accelerometer's mass when the data say it was off the beam), with its NRMSE fits.

        Parameters
        ----------
        model : station.plant.model.Model or station.plant.DiscretePlant
            A Model is simulated at the log's sample time with its effects; a
            DiscretePlant (reset first) should have the log's dt.
        sensors : bool, default True
            Also give the model the sensor and wiring faults this run's data decided
            (:meth:`found_faults`: a reversed accelerometer, encoder or motor), as the audit says
            them; a diagnosis, which decides them over all its runs, passes False.

        Returns
        -------
        ModelRun

        Raises
        ------
        StationError
            The log lacks a column the simulation or its θ fit needs (:attr:`simulated_columns`).
        """
        if not self._simulable:  # checked once: a diagnosis simulates a run thousands of times
            self.check_columns(self.simulated_columns, "simulating it on a model")
            self._simulable = True
        found = self.found_faults(model) if sensors else {}
        sim = simulate_log(self.log, self.controller, self.alignment, self.model_as_found(model, sensors),
                           self.ticks)
        if self.mounting.mounted is False:
            sim = dataclasses.replace(sim, how=sim.how + "; without the accelerometer's mass (the audit: no "
                                      "accelerometer on the beam)")
        if found:
            said = ", ".join(fault_text(k, v) for k, v in found.items())
            sim = dataclasses.replace(sim, how=sim.how + f"; with the sensor faults the audit decided from the "
                                      f"data ({said})")
        if sensors and self.sensors.doubt and not holds_signs(model):
            sim = dataclasses.replace(sim, how=sim.how + f"; {DOUBT_WORDS}{self.sensors.doubt}",
                                      doubt=self.sensors.doubt)
        return sim


def _skipped(log: RunLog) -> np.ndarray | None:
    status = log.data.get("status")
    if status is None or log.format != "station":
        return None
    mask = (np.nan_to_num(status).astype(np.int64) & SKIPPED) != 0
    return mask if mask.any() else None
