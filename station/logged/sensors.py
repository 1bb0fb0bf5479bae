"""The sensors' and the motor's signs and scales, decided from the data (DESIGN.md's sensor
and wiring faults: "decided from the data first where the data decide them").

A log claims, without saying so, that its θ counts 1024 per revolution in the model's
direction, that its a reads the tip's acceleration with the model's sign, and that a
positive command turns the motor the model's way. Driven open loop by the command the log
applied (its own v, so a closed loop's own feedback, right or wrong, is in it), the nominal
model moves as the rig moved if those claims hold. Two numbers per run test them
(:mod:`station.logged.sensor_evidence`):

- θ: the cosine between the measured and the modelled θ's changes over 50 ms where the
  measured hub moved (short, and moving, so the model's drift without friction does not
  count), and the least-squares ratio of the measured to the modelled changes;
- a: the cosine between the measured and the modelled a in each octave from 1 to 40 Hz (the
  accelerometer's offset and drift, and the beam's rigid motion, removed) where the model's a
  has a tenth of its largest octave's RMS, the median over those octaves; and a's least-squares ratio over the whole band, or,
  where the whole band's cosine (the runs' median) is below :data:`SIGN_COSINE`, over the
  octaves whose cosine reaches it. One cosine over the whole band is the largest octave's: a
  lightly damped mode the model puts off the rig's turns the phase around it, and where a
  run's a is mostly that mode (the lab's 2009 sweeps reach 20 Hz, the second mode: 30-36
  counts RMS at 14-20 Hz against 13-15 below) the whole band's cosine fell to −0.44 while
  every octave below the mode said −0.95 or less; on a blind sweep on a beam 20 % softer it
  was −0.04 and the ratio −0.04 (by octaves −0.77 and −0.96, the hidden gain −1.2).

A cosine below −:data:`SIGN_COSINE` is a reversal, above +:data:`SIGN_COSINE` the model's
sign, between them undecided. θ's sign is the encoder's times the motor's; a's the
accelerometer's times the motor's. Of the three wirings that give the two signs seen, the
one with fewest faults is decided (θ and a both reversed: the motor; θ alone: the encoder;
a alone: the accelerometer, its gain the median of a's ratio over θ's, in which the motion's
own scale cancels), and the other is said as the alternative. The accelerometer's
bias and drift are the least-squares fit of a on [1, t, the model's a]: decided when every
run's has one sign, their median reaches :data:`OFFSET_COUNTS` / :data:`DRIFT_COUNTS_PER_S` and every run's
is at least :data:`TREND_AGREEMENT` of it (a sensor's bias is in every run). The accelerometer's
gain is the median ratio of a; an encoder of another resolution is decided when every run's
θ ratio, and θ's over a's, are within :data:`SCALE_TOLERANCE` of one power of two other than 1 (a
4096-count encoder reads 4; the motion itself, and so a, as the model's), or when every run's
θ ratio over its a ratio is, within :data:`RATIO_TOLERANCE` (the motion's scale, friction's,
cancels), the inverse of their median is no accelerometer gain the fit searches (0.3-3), and
the encoder leaves the motion nearer the model's than an accelerometer gain would (θ's ratio
over the scale nearer 1 than θ's own). Otherwise a gain beyond the fit's search (another
sensitivity: 0.2 or 6, a model may hold 0.01-100) is decided from a's ratio over θ's where θ
itself moves within :data:`MOTION_RATIO` of the model's; past that the ratios do not decide and
it is said. One run alone decides a bias only where it reaches :data:`RUN_OFFSET_COUNTS` (a
channel stored without the rig's zeroing), far past what a model off in shape leaks into it,
or where a's rest before the first command reaches :data:`RUN_REST_OFFSET_COUNTS` (no model in
that).

On the rig's own logs (2009, 2013-14) every cosine is +0.74 or more where the channel
moves (``tests/test_sensor_signs.py``), on the lab's April 2009 session (its accelerometer
reversed) −0.86 or less; on the blind generator's reversed and rescaled
sensors the decided cosines are −0.88 or less and the ratios within 30 % of the hidden
values.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, field

from station.logged.audit import AuditClaim
from station.logged.sensor_evidence import ACCEL_OCTAVES_HZ, SIGN_COSINE, THETA_HORIZON_S, SensorEvidence
from station.plant.effects import EFFECTS, SENSOR_SIGNS
from station.rig import COUNTS_PER_REV

SCALE_TOLERANCE = 1.2
"""An encoder scale 2**k (k != 0) is decided when θ's ratio over a's is within this factor of it."""

RUN_OFFSET_COUNTS = 10.0
"""One run decides an accelerometer bias alone (its ``accel_bias``: a's rest value before the
first command plus the fit beside the model's a) when it is at least this large, counts: a
channel stored without the rig's zeroing, or a loop fed from it (Ga answers an unzeroed a from
its first sample: no rest). On the rig's 2009 and 2013-14 logs with the accelerometer on the tip
every run's is -1.93..+1.55; a model off in shape leaks 1.25 into one run's."""

RUN_REST_OFFSET_COUNTS = 4.0
"""... or where a's rest before the first command (:attr:`SensorEvidence.accel_rest`, at least
:data:`station.logged.sensor_evidence.REST_MIN_SAMPLES` samples: nothing of a model in it)
reaches this, counts, and the bias beside the model's a has its sign: about twice the rig's
largest rest (its 2009 and 2013-14 logs: -1.98..+2.20, the lead step's ten samples still
ringing). Below it one run leaves a bias to a session's runs (:data:`OFFSET_COUNTS`)."""

RUN_DRIFT_COUNTS_PER_S = 2.0
"""One run decides an accelerometer drift alone where the drift its integral gives
(:attr:`SensorEvidence.accel_integral_drift`: the tip at rest before its first command and at its
end, no model in it) is at least this large, counts per s, and the drift beside the model's a
has its sign: the rig's logs that end at rest give -0.27..+0.22 counts per s, the blind
generator's runs without a drift -0.82..+0.70 (every case of friction, dead-zone, drive damping,
delay, a sensor reversed, ..., four seeds)."""

OFFSET_COUNTS = 1.0
"""An accelerometer bias is decided when every run's has one sign and their median is at least
this large, counts (the noise is 0.3; the rig's 2013-14 runs' biases take both signs)."""

DRIFT_COUNTS_PER_S = 0.75
"""An accelerometer drift is decided when every run's has one sign and their median is at least
this large, counts per s (the rig's runs: |median| under 0.1)."""

TREND_AGREEMENT = 0.5
"""... and when every run's bias (or drift) is at least this share of their median: the
sensor's own is in every run, whatever the run did, where a model whose motion is off leaks
into the runs it moves wrongly (blind, an encoder reversed beside drive damping 0.49: 3.0-3.5
counts in the three closed-loop steps, 0.01 in the open-loop pulses, decided 3.28 before)."""

RATIO_TOLERANCE = 1.3
"""θ's ratio over a's may sit within this factor of the encoder's scale in each run: friction
does not slow θ and a quite alike (3.2-4.2 for a 4096-count encoder beside 26-29 counts)."""

THETA_HEADER = "θ: encoder counts, 1024 per revolution, turning with the command as the model's"
ACCEL_HEADER = "a: the tip's acceleration with the model's sign"
OFFSET_HEADER = "a: zero at rest (the rig zeroes it before a test)"
DRIFT_HEADER = "a: no drift over a run"
SCALE_HINT_HEADER = "θ: 1024 encoder counts per revolution"
"""The header of the claim θ's and a's ratios point at but do not decide (:attr:`SensorFaults.doubt`)."""
DOUBT_WORDS = "not decided by the data: "
"""How replay, compare and survey say :attr:`SensorFaults.doubt` beside a fit."""
"""The headers of the accelerometer's bias and drift claims (decided over a session's runs)."""
SESSION_HEADERS = (THETA_HEADER, ACCEL_HEADER, OFFSET_HEADER, DRIFT_HEADER)
"""The headers of the sensors' "columns" claims a diagnosis decides over all its runs and says
once, not each run's (:attr:`station.logged.LoggedRun.sensors`): the signs and scales, and the
accelerometer's bias and drift."""
REFINED_BY_FIT = "; the decision's first estimate {first}, refined by the fit"
REFINED_BY_MODEL = ", the model's; this run alone gives {first}"
"""How a reversed accelerometer's claim says a gain found otherwise beside the data's own
estimate: a diagnosis's fit refines it; a saved model holds its session's."""

MOTION_RATIO = 2.5
"""An accelerometer gain beyond the fit's search is decided only where θ's ratio is within this
factor of the model's (θ read right, the motion is the model's up to friction or the actuator's
gain, whose search spans 0.4-2.5 blind); past it, θ's scale is in doubt too and the ratios do not
decide which (a θ written 32 times over: an encoder of 32768 counts past :data:`ENCODER_SCALES`,
said as the hint, not an accelerometer gain of 0.04)."""

ENCODER_SCALES = (0.25, 0.5, 2.0, 4.0, 8.0, 16.0)
"""Encoder resolutions decided, relative to the model's 1024 counts per revolution."""


def _sign(cosines: list[float]) -> int:
    """+1, -1 or 0 (undecided) from the runs' cosines (their median)."""
    if not cosines:
        return 0
    c = statistics.median(cosines)
    return 1 if c >= SIGN_COSINE else -1 if c <= -SIGN_COSINE else 0


@dataclass(frozen=True)
class SensorFaults:
    """The sensor and wiring faults the data decide, over one rig's runs.

    Attributes
    ----------
    effects : dict of str to float
        Decided effects (accel_gain, accel_offset, accel_drift, encoder_scale,
        motor_polarity) -> value; empty when the data agree with the model's signs and scales.
        A diagnosis holds them all in its base model (an accelerometer bias with each run's a
        as logged: :func:`station.diagnosis.runs.cases.keep_bias`).
    claims : tuple of AuditClaim
        "columns" claims: θ's and a's signs and scale, confirmed, contradicted or unchecked.
    alternative : str
        The other wiring that gives the same signs ("" when none).
    evidence : tuple of SensorEvidence
        Per run.
    to_fit : tuple of str
        Faults the data point at but do not decide: a diagnosis fits them as candidates
        (an encoder of another resolution beside a slower motion).
    first : dict of str to float
        The decision's first estimate of a fault whose value a fit refined (:meth:`refined`:
        ``effects`` holds the fitted value, the model's); empty when none was refined.
    trends : bool
        Whether the accelerometer's bias and drift were decided over a session's runs
        (:func:`decide_faults`' ``trends``); :meth:`refined` decides again by the same rule.
    """

    effects: dict = field(default_factory=dict)
    claims: tuple = ()
    alternative: str = ""
    evidence: tuple = ()
    to_fit: tuple = ()
    first: dict = field(default_factory=dict)
    trends: bool = True

    def refined(self, values, by: str = REFINED_BY_FIT) -> SensorFaults:
        """The same faults holding the values a model holds: a diagnosis's fit refines a
        reversed accelerometer's gain beside the effects it accepts, and the record it reports
        (its lines, its JSON, the saved model) says the value the model holds, and the
        decision's first estimate beside it where they differ. A run compared with a model
        that holds its own (one a diagnosis saved) says the model's value the same way.

        Parameters
        ----------
        values : mapping of str to float
            The model's effects (e.g. the extended model's ``effect_dict()``).
        by : str, default :data:`REFINED_BY_FIT`
            How the accelerometer's claim says the two values, after the model's
            (a format with ``{first}``; :data:`REFINED_BY_MODEL` beside a saved model).

        Returns
        -------
        SensorFaults
            Itself when the model holds the decided values.
        """
        g, first = values.get("accel_gain"), self.effects.get("accel_gain")
        if g is None or first is None or (g < 0) != (first < 0) or f"{g:.3g}" == f"{first:.3g}":
            return self
        return decide_faults(self.evidence, accel_gain=g, trends=self.trends, refined_by=by)

    @property
    def doubt(self) -> str:
        """What the data point at but do not decide (:attr:`to_fit`: an encoder of another
        resolution or the accelerometer's gain), "" when nothing."""
        return next((c.evidence for c in self.claims if c.header == SCALE_HINT_HEADER), "")

    def lines(self) -> list[str]:
        """One line per contradicted claim, then the other wiring the same signs fit (never
        read as a second fault)."""
        return self._claimed() + self._undecided()

    def _claimed(self) -> list[str]:
        return [c.line for c in self.claims if c.verdict == "contradicted"]

    @property
    def undecided_wiring(self) -> str:
        """The other wiring that reads the signs of the faults decided ("" when none is
        decided): a rival no fit can tell apart (the same θ and a for every v)."""
        return self.alternative if self._claimed() else ""

    def _undecided(self) -> list[str]:
        w = self.undecided_wiring
        return [f"{w} would read the same signs; the model holds the fewest faults"] if w else []

    def said(self) -> list[str]:
        """The lines as every output says them (diagnose, survey, the report, the progress).

        Returns
        -------
        list of str
            Each contradicted claim after "sensor fault, decided from the data: ", then the
            wiring the data cannot tell from it after "sensor wiring, not decided by the data: ".
        """
        return ([f"sensor fault, decided from the data: {line}" for line in self._claimed()]
                + [f"{UNDECIDED_WIRING}{line}" for line in self._undecided()])

    def to_json(self) -> dict:
        """``{"effects", "first_estimates", "claims", "alternative", "to_fit", "runs"}``."""
        return {"effects": dict(self.effects), "first_estimates": dict(self.first),
                "claims": [c.to_json() for c in self.claims], "alternative": self.alternative,
                "to_fit": list(self.to_fit), "runs": [dict(vars(e)) for e in self.evidence]}


def _fmt(values: list[float]) -> str:
    return ", ".join(f"{v:+.2f}" for v in values)


UNDECIDED_WIRING = "sensor wiring, not decided by the data: "
"""Before the other wiring that reads the signs seen: no rival a fit could tell apart (the
same θ and a for every v), so not one of a diagnosis's alternatives."""

NO_FAULTS = SensorFaults()
"""Nothing decided (a run without the evidence: no rows, a beam test)."""


def decide_faults(evidence: Sequence[SensorEvidence], accel_gain: float | None = None,
                  trends: bool = True, refined_by: str = REFINED_BY_FIT) -> SensorFaults:
    """Decide the sensors' signs and scales from the runs' evidence (module docstring).

    Parameters
    ----------
    evidence : sequence of SensorEvidence
        One per run of one rig (one session).
    accel_gain : float, optional
        A reversed accelerometer's gain found otherwise (a diagnosis refits it beside the
        effects it accepted: :meth:`SensorFaults.refined`); held as given, the decision's own
        estimate (a's ratio over θ's, the median over the runs, the default) in ``first``.
    trends : bool, default True
        Also decide the accelerometer's bias and drift. Over one run they are not decided
        (:attr:`station.logged.LoggedRun.sensors`): a model's a that is off in shape leaks
        into one run's fit of bias and slope (the thesis's lead + accelerometer step: −1.25
        counts and 0.98 counts per s), where a session's runs agreeing in sign do not.
        Without them, a bias is still decided where every run's reaches
        :data:`RUN_OFFSET_COUNTS`, far past any such leak.
    refined_by : str, default :data:`REFINED_BY_FIT`
        How the accelerometer's claim says ``accel_gain`` beside the first estimate (a
        format with ``{first}``).

    Returns
    -------
    SensorFaults
    """
    ev = tuple(evidence)
    th_cos = [e.theta_cosine for e in ev if e.theta_cosine is not None]
    a_cos = [e.accel_cosine for e in ev if e.accel_cosine is not None]
    s_th, s_a = _sign(th_cos), _sign(a_cos)
    effects: dict[str, float] = {}
    first: dict[str, float] = {}
    alternative = hint = ""
    if s_th < 0 and s_a < 0:
        effects["motor_polarity"] = -1.0
        alternative = "the encoder and the accelerometer both reversed (encoder_scale -1, accel_gain -1)"
    elif s_th < 0:
        effects["encoder_scale"] = -1.0
        alternative = ("the motor and the accelerometer reversed (motor_polarity -1, accel_gain -1)" if s_a > 0 else
                       "the motor reversed (motor_polarity -1): θ alone cannot tell them apart")
    elif s_th > 0 and s_a < 0:
        effects["accel_gain"] = -1.0
        alternative = "the encoder and the motor both reversed (encoder_scale -1, motor_polarity -1)"
    # magnitudes: a's gain from its ratio, the encoder's from θ's ratio over a's
    motor = effects.get("motor_polarity", 1.0)
    # a's ratio is the whole band's where the whole band has the model's shape (the median of
    # its cosines decides too); where only the octaves decide, the octaves' with the shape
    band_cos = [e.accel_band_cosine for e in ev if e.accel_band_cosine is not None]
    shaped = bool(band_cos) and abs(statistics.median(band_cos)) < SIGN_COSINE
    ratios = [e.accel_shaped_ratio if shaped else e.accel_ratio for e in ev]
    a_ratio = [r * motor for r in ratios if r is not None]
    th_ratio = [e.theta_ratio * motor for e in ev if e.theta_ratio is not None]
    spec = EFFECTS["accel_gain"]
    if s_a != 0 and a_ratio:
        g_a = statistics.median(a_ratio)
        # a's ratio over θ's per run: the motion's own scale (friction, the actuator) cancels
        per_run = [r * motor / abs(e.theta_ratio) for e, r in zip(ev, ratios) if r is not None
                   and e.theta_ratio is not None and abs(e.theta_ratio) >= 0.1]
        lo, hi = spec.bounds
        size = min(max(abs(statistics.median(per_run) if per_run else g_a), lo), hi)
        own = float(f"{math.copysign(size, g_a):.3g}")
        if effects.get("accel_gain", 1.0) < 0 and g_a < 0:
            _decide_gain(own, accel_gain, effects, first)
        if s_th != 0 and th_ratio and g_a != 0:
            g_th = abs(statistics.median(th_ratio))
            scale = min(ENCODER_SCALES, key=lambda s: abs(math.log(g_th / s)))
            # θ off by a power of two where a is not: the encoder's resolution, not the motion's
            tol = math.log(SCALE_TOLERANCE)
            near = (all(r != 0 and abs(math.log(abs(r) / scale)) <= tol for r in th_ratio)
                    and abs(math.log(g_th / abs(g_a) / scale)) <= tol)
            q = g_th / abs(g_a)
            # θ over a per run, the motion's own scale (friction) cancelling: a power of two whose
            # inverse no accelerometer gain of the vocabulary reaches is the encoder's
            qs = [abs(e.theta_ratio / r) for e, r in zip(ev, ratios)
                  if e.theta_ratio is not None and r not in (None, 0.0)]
            if not near and qs:
                by_q = min(ENCODER_SCALES, key=lambda s: abs(math.log(statistics.median(qs) / s)))
                med = statistics.median(qs)
                # ... and the encoder leaves the motion nearer the model's than an accelerometer
                # gain would: θ read right, the motion is θ's ratio; a read right, it is a's
                near = (all(abs(math.log(x / by_q)) <= math.log(RATIO_TOLERANCE) for x in qs)
                        and not spec.searched(1.0 / med)
                        and abs(math.log(g_th / by_q)) < abs(math.log(g_th)))
                scale = by_q if near else scale
            if near:
                effects["encoder_scale"] = scale * (-1.0 if effects.get("encoder_scale", 1.0) < 0 else 1.0)
            elif s_a * motor > 0 and "accel_gain" not in effects and not spec.searched(own) and \
                    abs(math.log(g_th)) <= math.log(MOTION_RATIO):
                # a read at a gain beyond the fit's search (another sensitivity), θ moving as the
                # model's up to what an effect gives (both read through a reversed motor too): the
                # data decide it
                _decide_gain(own, accel_gain, effects, first)
            elif q >= 2.0 / SCALE_TOLERANCE or q <= 0.5 * SCALE_TOLERANCE:
                # θ off from a by a power of two, but the motion is off too: an encoder of another
                # resolution beside friction or an actuator gain, or the accelerometer's gain
                # θ slower than the model and than a: friction holds the hub while the beam rings
                held = ", or friction holding the hub while the beam rings" if q < 1 and g_th < 1 else ""
                hint = (f"θ reads {q:.2f}× what a's motion gives (θ's ratio {g_th:.2f}, a's {abs(g_a):.2f}): "
                        f"an encoder of {q * COUNTS_PER_REV:.0f} counts per revolution, or the accelerometer's gain"
                        f"{held}; the ratios do not decide it")
    bias_claim = drift_claim = None
    biases = [e.accel_bias for e in ev if e.accel_bias is not None and math.isfinite(e.accel_bias)]
    rests = [e.accel_rest for e in ev if e.accel_bias is not None and math.isfinite(e.accel_bias)]
    one_sign = bool(biases) and (all(b > 0 for b in biases) or all(b < 0 for b in biases))
    unzeroed = one_sign and all(abs(b) >= RUN_OFFSET_COUNTS for b in biases)
    at_rest = one_sign and all(r is not None and abs(r) >= RUN_REST_OFFSET_COUNTS and r * b > 0
                               for r, b in zip(rests, biases))
    if not trends and (unzeroed or at_rest):
        effects["accel_offset"] = _counts(statistics.median(biases))
        said = (f"bias per run beside the model's a: {_fmt(biases)} counts (the rig's zeroing leaves under "
                f"{RUN_OFFSET_COUNTS:g}): a channel stored without it" if unzeroed else
                f"a at rest before the first command: {_fmt(rests)} counts (the rig's zeroing leaves under "
                f"{RUN_REST_OFFSET_COUNTS:g}); bias per run beside the model's a: {_fmt(biases)} counts")
        bias_claim = AuditClaim("columns", OFFSET_HEADER, f"accel_offset {effects['accel_offset']:g} counts",
                                "contradicted", said)
    integral = [e.accel_integral_drift for e in ev if e.accel_bias is not None and math.isfinite(e.accel_bias)]
    slopes = [e.accel_slope for e in ev if e.accel_bias is not None and math.isfinite(e.accel_bias)]
    if not trends and integral and all(d is not None and abs(d) >= RUN_DRIFT_COUNTS_PER_S and d * m > 0
                                       for d, m in zip(integral, slopes)):
        effects["accel_drift"] = _counts(statistics.median(integral))
        drift_claim = AuditClaim(
            "columns", DRIFT_HEADER, f"accel_drift {effects['accel_drift']:g} counts per s", "contradicted",
            f"a's integral from the first command to the run's end, the tip at rest at both: {_fmt(integral)} "
            f"counts per s (the rig's runs under {RUN_DRIFT_COUNTS_PER_S:g}); drift per run beside the model's a: "
            f"{_fmt(slopes)} counts per s")
    if trends:
        bias_claim = _trend_claim("accel_offset", [e.accel_bias for e in ev], OFFSET_COUNTS, effects,
                                  OFFSET_HEADER, "counts")
        drift_claim = _trend_claim("accel_drift", [e.accel_slope for e in ev], DRIFT_COUNTS_PER_S, effects,
                                   DRIFT_HEADER, "counts per s")
    claims = [_theta_claim(s_th, th_cos, th_ratio, a_ratio, effects),
              _accel_claim(s_a, a_cos, effects, first, refined_by),
              bias_claim, drift_claim]
    if hint:
        claims.append(AuditClaim("columns", SCALE_HINT_HEADER, "undecided", "unchecked", hint))
    return SensorFaults(effects, tuple(c for c in claims if c is not None), alternative, ev,
                        ("encoder_scale",) if hint else (), first, trends)


def holds_signs(model) -> bool:
    """Whether a model holds sensors' signs or scales of its own (one a diagnosis saved): a run's
    own decision is then not applied to it, its claims say the model's values and its doubt is
    not said (:class:`station.logged.LoggedRun`).

    Parameters
    ----------
    model : station.plant.model.Model or station.plant.DiscretePlant
        A DiscretePlant holds no effects.

    Returns
    -------
    bool
        True where it holds any of :data:`station.plant.effects.SENSOR_SIGNS`.
    """
    return hasattr(model, "effect_dict") and any(k in model.effect_dict() for k in SENSOR_SIGNS)


def fault_text(name: str, value: float) -> str:
    """A sensor fault as every output says it: "accel_offset 114.36" (a bias or drift to a
    hundredth, :func:`_counts`), "accel_gain -1.36" (a gain or scale to three figures).

    Parameters
    ----------
    name : str
        A sensor or wiring fault (:data:`station.plant.effects.SENSOR_FAULTS`).
    value : float
    """
    return f"{name} {_counts(value):g}" if name in ("accel_offset", "accel_drift") else f"{name} {value:.3g}"


def _counts(x: float) -> float:
    """A decided bias (counts) or drift (counts per s) to a hundredth: three significant figures
    of an unzeroed channel's 114.37 counts leave 0.37, which Ga's DC gain of 18 makes a 7-count
    offset of the loop's reference."""
    return round(float(x), 2)


def _decide_gain(own: float, accel_gain: float | None, effects: dict, first: dict) -> None:
    """Hold the accelerometer's gain the data decide (``own``), or the one found otherwise
    (``accel_gain``: a fit refined it) with ``own`` as the first estimate."""
    effects["accel_gain"] = own
    if accel_gain is not None and f"{accel_gain:.3g}" != f"{own:.3g}":
        effects["accel_gain"], first["accel_gain"] = float(accel_gain), own


def _trend_claim(name: str, values, least: float, effects: dict, header: str, unit: str) -> AuditClaim | None:
    """Decide an accelerometer bias or drift (into ``effects``) when every run's has one sign,
    their median reaches ``least`` and every run's is at least :data:`TREND_AGREEMENT` of it;
    unchecked where all but the agreement hold (a run shows little of it: the model's motion,
    not the sensor)."""
    v = [x for x in values if x is not None and math.isfinite(x)]
    if not v:
        return None
    med = statistics.median(v)
    evidence = f"{name.split('_')[1]} per run beside the model's a: {_fmt(v)} {unit}"
    if abs(med) >= least and (all(x > 0 for x in v) or all(x < 0 for x in v)):
        if min(abs(x) for x in v) >= TREND_AGREEMENT * abs(med):
            effects[name] = _counts(med)
            return AuditClaim("columns", header, f"{name} {effects[name]:g} {unit}", "contradicted", evidence)
        return AuditClaim("columns", header, "undecided", "unchecked",
                          evidence + f" (a sensor's is in every run: some runs show less than "
                                     f"{TREND_AGREEMENT:g} of the median, a model whose motion is off there)")
    return AuditClaim("columns", header, "as claimed", "confirmed",
                      evidence + f" (decided at |median| >= {least:g} with one sign in every run)")


def _theta_claim(sign: int, cosines, th_ratio, a_ratio, effects) -> AuditClaim | None:
    if not cosines:
        return None
    header = THETA_HEADER
    evidence = (f"cosine of θ's {THETA_HORIZON_S * 1000:.0f} ms changes with the nominal model's, driven by the "
                f"logged command: {_fmt(cosines)} over {len(cosines)} run(s)")
    if th_ratio and a_ratio:
        evidence += f"; θ's ratio {statistics.median(th_ratio):.2f}, a's {statistics.median(a_ratio):.2f}"
    if sign == 0:
        return AuditClaim("columns", header, "undecided", "unchecked", evidence)
    if "motor_polarity" in effects:
        data = "the motor turns against the command (motor_polarity -1): θ and a both reversed"
    elif effects.get("encoder_scale", 1.0) != 1.0:
        s = effects["encoder_scale"]
        data = (f"the encoder counts {abs(s) * COUNTS_PER_REV:.0f} per revolution" if abs(s) != 1.0 else "the encoder") + \
               (" the other way" if s < 0 else "") + f" (encoder_scale {s:g})"
    else:
        return AuditClaim("columns", header, "as claimed", "confirmed", evidence)
    return AuditClaim("columns", header, data, "contradicted", evidence)


def _accel_claim(sign: int, cosines, effects, first, refined_by: str) -> AuditClaim | None:
    if not cosines:
        return None
    header = ACCEL_HEADER
    evidence = (f"cosine of a with the nominal model's (the median of its octaves' from {ACCEL_OCTAVES_HZ[0]:g} to "
                f"{ACCEL_OCTAVES_HZ[-1]:g} Hz): "
                f"{_fmt(cosines)} over {len(cosines)} run(s)")
    if sign == 0:
        return AuditClaim("columns", header, "undecided", "unchecked", evidence)
    g = effects.get("accel_gain", 1.0)
    if "accel_gain" in effects:
        value = f"accel_gain {g:.3g}" + (refined_by.format(first=f"{first['accel_gain']:.3g}")
                                         if "accel_gain" in first else "")
        data = ("the accelerometer reads the other way" if g < 0 else
                f"the accelerometer reads {g:.3g}× the model's a, beyond the fit's search "
                f"({EFFECTS['accel_gain'].lower:g}..{EFFECTS['accel_gain'].upper:g})")
        return AuditClaim("columns", header, f"{data} ({value})", "contradicted", evidence)
    return AuditClaim("columns", header, "as claimed" + (" (the motor's reversal aside)" if
                                                         "motor_polarity" in effects else ""), "confirmed", evidence)
