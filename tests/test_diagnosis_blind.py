"""Blind hidden-effect tests of the model diagnosis (issue 8, item 6).

An effect is hidden in the four rig-format logs of a case written by the independent
generator (tests/blind: its own FEM, friction and backlash integrated on a sub-step grid,
the rig's noise and quantization); :func:`station.diagnosis.diagnose` sees only
the log files. For every effect of tests.blind.cases.MAGNITUDES, two seeds with values
drawn in the issue's ranges: the cause must be named with its value within 25 %; a clean
case must give "none"; a two-effect case must name both. The ten-seed table is
scripts/validate_diagnosis.py's. Slow (about 25 s per case): marked ``slow``, run in CI.
"""

from __future__ import annotations

import pytest

from tests.blind.cases import MAGNITUDES, NEW_MAGNITUDES, TOLERANCE, TWO_EFFECTS, case_effects, value_error
from tests.blind.generator import write_case

pytestmark = pytest.mark.slow

SEEDS = (0, 1)


def _diagnose(tmp_path, effects, seed):
    from station.diagnosis import diagnose

    paths = write_case(tmp_path / "logs", effects, seed)
    return diagnose([str(p) for p in paths]).to_json()


def _value(result: dict, name: str) -> float:
    return next(e["value"] for e in result["effects"] if e["name"] == name)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("effect", list(MAGNITUDES))
def test_hidden_effect_is_named_with_its_value(tmp_path, effect, seed):
    effects = case_effects(effect, seed)
    result = _diagnose(tmp_path, effects, seed)
    hidden = effects[effect]
    assert result["cause"] == effect, f"hidden {effect} = {hidden:.4g}: found {result['causes']}"
    found = _value(result, effect)
    assert value_error(hidden, found) <= TOLERANCE, f"{effect}: hidden {hidden:.4g}, found {found:.4g}"
    assert result["gain_pct"] > 0


@pytest.mark.parametrize("seed", SEEDS)
def test_clean_case_gives_none(tmp_path, seed):
    result = _diagnose(tmp_path, {}, seed)
    assert result["cause"] == "none", result["causes"]
    assert result["causes"] == [] and result["gain_pct"] == 0


def test_two_hidden_effects_are_both_named(tmp_path):
    effects = case_effects("two", 0)
    result = _diagnose(tmp_path, effects, 0)
    assert set(TWO_EFFECTS) <= set(result["causes"]), f"hidden {effects}: found {result['causes']}"
    for name in TWO_EFFECTS:
        found = _value(result, name)
        assert value_error(effects[name], found) <= TOLERANCE, f"{name}: hidden {effects[name]:.4g}, found {found:.4g}"


def _joint(result: dict, name: str) -> float:
    """The value in the extended (joint) model."""
    return result["extended_model"]["effects"][name]


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("effect", list(NEW_MAGNITUDES))
def test_new_hidden_effect_is_named_with_its_value(tmp_path, effect, seed):
    effects = case_effects(effect, seed)
    result = _diagnose(tmp_path, effects, seed)
    hidden = effects[effect]
    assert result["cause"] == effect, f"hidden {effects}: found {result['causes']}"
    found = _joint(result, effect)
    assert value_error(hidden, found) <= TOLERANCE, f"{effect}: hidden {hidden:.4g}, found {found:.4g}"
    if effect == "static_friction":  # breakaway friction: one cause, its sliding level beside it
        assert "coulomb_friction" in result["extended_model"]["effects"]
        assert "coulomb_friction" not in result["causes"]


@pytest.mark.parametrize("case, seed", [
    ("coulomb_friction+amp_offset", 0),
    # a miss before the last look (station.diagnosis.search.stepwise): a dead-zone taken first
    # for Coulomb friction plus an offset, drive damping beside it, and no offset paid beside both
    ("amp_offset+coulomb_friction+param:drive_c", 0),
    # a miss before the swap: the actuator pole taken at the third step for a delay of 1 sample,
    # which paid in its place only once breakaway friction replaced the Coulomb friction
    ("static_friction+amp_offset+delay", 0),
    # before the lookahead (station.diagnosis.search.stepwise) 0 of 10: Coulomb friction came first
    # and backlash never paid beside it; seed 0 named coulomb_friction + param:drive_c
    ("viscous_friction+backlash", 0),
    # 5 of 10 before: a dead-zone came first; then the alternatives' refit failed on the
    # breakaway friction the lookahead reached (static_friction's sliding level not held)
    ("static_friction+param:drive_c", 0),
])
def test_new_effects_in_pairs_and_triples_are_all_named(tmp_path, case, seed):
    effects = case_effects(case, seed)
    result = _diagnose(tmp_path, effects, seed)
    # breakaway friction is one cause, judged on v_s; its sliding level is in the model beside it
    judged = {k: v for k, v in effects.items() if not (k == "coulomb_friction" and "static_friction" in effects)}
    assert set(judged) <= set(result["causes"]), f"hidden {effects}: found {result['causes']}"
    if "static_friction" in effects:
        assert "coulomb_friction" in result["extended_model"]["effects"]
    for name, hidden in judged.items():
        found = _joint(result, name)
        assert value_error(hidden, found) <= TOLERANCE, f"{name}: hidden {hidden:.4g}, found {found:.4g}"


def _holds_within(hidden: dict, causes, values: dict) -> bool:
    """Every hidden effect a cause (a breakaway's sliding level in the values) within 25 %."""
    held = {"coulomb_friction"} if "static_friction" in causes else set()
    return all((k in causes or k in held) and k in values and value_error(v, values[k]) <= TOLERANCE
               for k, v in hidden.items())


@pytest.mark.parametrize("hidden, seed, alignment", [
    # breakaway 13.5 over 5.9: the four runs fit plain Coulomb friction 6.07 as well (issue 26)
    (case_effects("breakaway_sliding", 8), 8, 1),
    # issue 26's case: Coulomb friction + drive stiffness named before the joint screen
    ({"static_friction": 14.0, "coulomb_friction": 9.0, "amp_offset": 2.5}, 0, 0),
    # an offset of 6.8 above the sliding level 4.7: the open-loop hub runs away unless the
    # breakaway (11.1) holds it, so no single effect paid and the answer was "none" at J 543
    # (the hidden triple's 1.03) before the pair start (station.diagnosis.search.stepwise)
    (case_effects("breakaway_sliding+amp_offset@d0", 7), 7, 0),
], ids=["breakaway_sliding-8", "issue-26-d0", "runaway-offset-d0-7"])
def test_a_breakaway_over_a_sliding_level_is_named_or_its_rival_kept(tmp_path, hidden, seed, alignment):
    """Both levels named within 25 %, or the explanation holding them among the alternatives:
    the doubt stays until the data settle it."""
    from station.diagnosis import diagnose

    paths = write_case(tmp_path / "logs", hidden, seed, alignment=alignment)
    result = diagnose([str(p) for p in paths]).to_json()
    answer = _holds_within(hidden, result["causes"], result["extended_model"]["effects"])
    rival = [a for a in result["alternatives"] if _holds_within(hidden, a["causes"], a["values"])]
    assert answer or rival, (hidden, result["causes"], result["extended_model"]["effects"], result["alternatives"])


def test_a_breakaway_that_pays_only_by_luck_keeps_plain_coulomb_friction_as_its_rival(tmp_path):
    """The mirror of the test above: plain Coulomb friction 28.4 (the motor reversed, seed 0)
    named as a breakaway of 57 over it, which pays over the Coulomb friction only when both are
    judged by their luck; the data cannot tell them apart, so the Coulomb friction stays among
    the alternatives (it ended with none)."""
    effects = case_effects("motor_reversed+coulomb_friction", 0)
    result = _diagnose(tmp_path, effects, 0)
    if "static_friction" not in result["causes"]:  # the plain level named: nothing to doubt here
        assert "coulomb_friction" in result["causes"], result["causes"]
        return
    rivals = [a for a in result["alternatives"]
              if "coulomb_friction" in a["causes"] and "static_friction" not in a["causes"]]
    assert rivals, result["alternatives"]
    assert value_error(effects["coulomb_friction"], rivals[0]["values"]["coulomb_friction"]) <= TOLERANCE


def test_plain_coulomb_friction_beside_a_4096_count_encoder_is_not_a_breakaway(tmp_path):
    """Seed 1 named a breakaway over the right sliding level until credible weighed it against
    the luck around plain Coulomb friction (issue 26)."""
    effects = case_effects("encoder_4096+coulomb_friction", 1)
    result = _diagnose(tmp_path, effects, 1)
    assert "coulomb_friction" in result["causes"] and "static_friction" not in result["causes"], result["causes"]
    assert value_error(effects["coulomb_friction"], _joint(result, "coulomb_friction")) <= TOLERANCE


def test_validation_script_writes_the_table(tmp_path, monkeypatch):
    import importlib.util
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "scripts" / "validate_diagnosis.py"
    spec = importlib.util.spec_from_file_location("validate_diagnosis", script)
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, module)  # its dataclass looks itself up there
    spec.loader.exec_module(module)
    out = tmp_path / "table.md"
    assert module.main(["--seeds", "1", "--effects", "clean", "--out", str(out)]) == 0
    text = out.read_text()
    assert "| effect | hidden range |" in text
    assert 'Clean cases: "none" with `unexplained: false` in 1 of 1' in text
    assert "| clean | 0 | - | none |" in text
    # the verdicts: a clean rig flagged unexplained is a miss; an out-of-vocabulary effect must be flagged
    outcome = module.Outcome
    assert not outcome("clean", 0, {}, [], {}, 0.0, 1.0, unexplained=True).ok
    assert outcome("oov:cogging", 0, {}, ["coulomb_friction"], {}, 0.0, 1.0, unexplained=True).ok
    assert not outcome("oov:cogging", 0, {}, [], {}, 0.0, 1.0, unexplained=False).ok
    # a breakaway over a sliding level: both levels named, or the rival holding them in alternatives
    hidden = {"static_friction": 14.0, "coulomb_friction": 9.0, "amp_offset": 2.5}
    found = {"coulomb_friction": 9.16, "amp_offset": 2.5}
    rival = {"causes": ["static_friction", "amp_offset"], "cost_ratio": 0.95,
             "values": {"static_friction": 14.0, "amp_offset": 2.54, "coulomb_friction": 9.05}}
    case = "breakaway_sliding+held_offset@d0"
    assert module.judged(case) == ("static_friction", "coulomb_friction", "amp_offset")
    assert not outcome(case, 0, hidden, ["coulomb_friction", "amp_offset"], found, 0.0, 1.0, found).ok
    assert outcome(case, 0, hidden, ["coulomb_friction", "amp_offset"], found, 0.0, 1.0, found,
                   alternatives=[rival]).ok
    far = {**rival, "values": {**rival["values"], "coulomb_friction": 5.0}}  # v_c 44 % off: no rival
    assert not outcome(case, 0, hidden, ["coulomb_friction", "amp_offset"], found, 0.0, 1.0, found,
                       alternatives=[far]).ok
    both = {**found, "static_friction": 13.0, "coulomb_friction": 8.0}
    assert outcome(case, 0, hidden, ["static_friction", "amp_offset"], both, 0.0, 1.0, both).ok
    # the old rows keep their bar: a rival in alternatives does not make a miss right
    assert not outcome("coulomb_friction", 0, {"coulomb_friction": 9.0}, ["deadzone"], {"coulomb_friction": 4.0},
                       0.0, 1.0, {"deadzone": 9.0}, alternatives=[{"causes": ["coulomb_friction"],
                                                                 "values": {"coulomb_friction": 9.0}}]).ok
