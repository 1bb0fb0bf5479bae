"""Model files (DESIGN.md "Model file") and the effect vocabulary (station.plant.effects)."""

import dataclasses
import math

import pytest

from station.errors import StationError
from station.plant import load_params
from station.plant.effects import CANDIDATES, EFFECTS, check_effects
from station.plant.model import Model, builtin_models, load_model


def test_builtin_tmm_fit_is_the_nominal_four_element_model():
    m = load_model("tmm-fit")
    assert "tmm-fit" in builtin_models()
    assert m.params == load_params("tmm-fit") and m.n_elements == 4 and m.effects == ()
    assert load_model() == m


def test_vocabulary_matches_design():
    named = {"coulomb_friction", "deadzone", "saturation", "delay", "backlash", "beam_damping", "accel_gain",
             "static_friction", "viscous_friction", "amp_offset"}
    params = {"mu", "EI", "drive_k", "drive_c", "clamp_k", "clamp_c", "J_base", "m_accel", "J_accel", "act_K",
              "act_p"}
    faults = {"accel_offset", "accel_drift", "encoder_scale", "motor_polarity"}  # besides accel_gain
    # stribeck_speed: a setting of static_friction in a model file, never a candidate cause;
    # accel_mounted: the rig's configuration (the accelerometer on the beam or not), never one either
    assert set(EFFECTS) == named | faults | {f"param:{p}" for p in params} | {"stribeck_speed", "accel_mounted"}
    assert "accel_mounted" not in CANDIDATES and EFFECTS["accel_mounted"].admits(0.0)
    assert not EFFECTS["accel_mounted"].admits(0.5) and EFFECTS["accel_mounted"].neutral == 1.0
    assert set(CANDIDATES) == named | {f"param:{p}" for p in params} and len(CANDIDATES) == 21
    assert EFFECTS["stribeck_speed"].neutral == 0.05 and EFFECTS["stribeck_speed"].unit == "rad/s"
    assert EFFECTS["viscous_friction"].unit == "DAC counts per rad/s" and EFFECTS["amp_offset"].neutral == 0.0
    assert EFFECTS["amp_offset"].lower < 0 < EFFECTS["amp_offset"].upper
    assert EFFECTS["saturation"].neutral == math.inf and EFFECTS["accel_gain"].neutral == 1.0
    assert EFFECTS["beam_damping"].neutral == pytest.approx(0.0054, abs=1e-4)  # DESIGN.md: tmm-fit 0.0054
    assert EFFECTS["backlash"].unit == "encoder counts" and EFFECTS["delay"].unit == "samples"


def test_round_trip_through_toml(tmp_path):
    m = load_model().with_effects({"coulomb_friction": 5.0, "param:drive_c": 2.0, "saturation": 180.0,
                                   "delay": 2.0}, name="rig-2013")
    path = tmp_path / "m.toml"
    m.save(path)
    text = path.read_text()
    assert 'params = "tmm-fit"' in text and '"param:drive_c" = 2.0' in text
    assert load_model(path) == m


def test_round_trip_of_a_parameter_set_that_is_not_a_file(tmp_path):
    p = dataclasses.replace(load_params(), drive_c=0.2)
    m = Model("custom", p, 3, (("backlash", 4.0),), params_source="tmm-fit")
    m.save(tmp_path / "c.toml")
    back = load_model(tmp_path / "c.toml")
    assert back.params == p and back.n_elements == 3 and back.effect_dict() == {"backlash": 4.0}


def test_params_path_is_relative_to_the_model_file(tmp_path):
    (tmp_path / "sets").mkdir()
    src = load_params.__globals__["PARAMS_DIR"] / "tmm-fit.toml"
    (tmp_path / "sets" / "mine.toml").write_text(src.read_text().replace("drive_k = 0.1027", "drive_k = 0.2027"))
    (tmp_path / "m.toml").write_text('params = "sets/mine.toml"\nn_elements = 2\n')
    m = load_model(tmp_path / "m.toml")
    assert m.params.drive_k == pytest.approx(0.20272834719157942) and m.n_elements == 2 and m.name == "m"


def test_overrides_of_elements_and_params():
    m = load_model("tmm-fit", n_elements=7)
    assert m.n_elements == 7


def test_neutral_value_removes_an_effect():
    m = load_model().with_effects({"deadzone": 4.0, "accel_gain": 1.5})
    assert m.with_effects({"deadzone": 0.0}).effect_dict() == {"accel_gain": 1.5}
    assert m.nominal().effects == ()
    assert m.effect("saturation") == math.inf


@pytest.mark.parametrize("body, key", [
    ('n_elements = 4\nfoo = 1\n', "foo"),
    ('n_elements = "four"\n', "n_elements"),
    ('n_elements = 0\n', "n_elements"),
    ('params = "no-such-set"\n', "params"),
    ('[effects]\nfriction = 3.0\n', "friction"),
    ('[effects]\ncoulomb_friction = 99.0\n', "coulomb_friction"),
    ('[effects]\ndelay = 1.5\n', "delay"),
    ('[effects]\n"param:k_tau" = 2.0\n', "param:k_tau"),
    ('[effects]\naccel_gain = "x"\n', "accel_gain"),
    ('[effects]\ncoulomb_friction = 8.0\nstatic_friction = 5.0\n', "static_friction"),
    ('[effects]\nstribeck_speed = 0.0\n', "stribeck_speed"),
    ('[effects]\namp_offset = -25.0\n', "amp_offset"),
    ('name = 3\n', "name"),
])
def test_bad_file_is_one_line_naming_file_and_key(tmp_path, body, key):
    path = tmp_path / "bad.toml"
    path.write_text("# a model\n" + body)
    with pytest.raises(StationError) as exc:
        load_model(path)
    msg = str(exc.value)
    assert "\n" not in msg and str(path) in msg and key in msg
    assert "line " in msg  # the key's line in the file


def test_missing_file_and_invalid_toml(tmp_path):
    with pytest.raises(StationError, match="model file not found.*tmm-fit"):
        load_model("no-such-model")
    bad = tmp_path / "x.toml"
    bad.write_text("name = \n")
    with pytest.raises(StationError, match=f"{bad}: not valid TOML"):
        load_model(bad)


def test_check_effects_names_where():
    with pytest.raises(StationError, match=r"^--effect: unknown effect 'stiction'"):
        check_effects({"stiction": 1.0}, "--effect")
    assert check_effects({"saturation": math.inf, "delay": 3}) == {"saturation": math.inf, "delay": 3.0}
    with pytest.raises(StationError, match="saturation"):
        check_effects({"saturation": 20.0})


def test_param_ratio_and_beam_damping_rebuild_the_linear_part():
    from station.plant.modes import modal_summary

    m = load_model()
    assert m.with_effects({"param:drive_c": 1.0}).linear_params() == m.params
    assert m.with_effects({"param:drive_c": 2.0}).linear_params().drive_c == 2.0 * m.params.drive_c
    damped = m.with_effects({"beam_damping": 0.05}).linear_params()
    assert modal_summary(damped, 4).antiresonance_damping[0] == pytest.approx(0.05, rel=1e-6)


def test_to_json_records_name_params_and_effects():
    j = load_model().with_effects({"backlash": 3.0}).to_json()
    assert j["name"] == "tmm-fit" and j["params"] == "tmm-fit" and j["effects"] == {"backlash": 3.0}
    assert j["parameters"]["drive_k"] == load_params().drive_k and j["n_elements"] == 4


def test_new_effects_round_trip_through_toml_and_the_log_header(tmp_path):
    fx = {"coulomb_friction": 6.0, "static_friction": 11.0, "stribeck_speed": 0.1, "viscous_friction": 2.5,
          "amp_offset": -2.0}
    m = load_model().with_effects(fx, name="rig-like")
    m.save(tmp_path / "m.toml")
    text = (tmp_path / "m.toml").read_text()
    assert '"stribeck_speed" = 0.1' in text and '"amp_offset" = -2.0' in text
    back = load_model(tmp_path / "m.toml")
    assert back == m and back.effect_dict() == fx
    assert m.to_json()["effects"] == fx  # what a simulated run's log header records
    # the default Stribeck speed is no setting at all
    assert m.with_effects({"stribeck_speed": 0.05}).effect("stribeck_speed") == 0.05
    assert "stribeck_speed" not in m.with_effects({"stribeck_speed": 0.05}).effect_dict()


def test_static_friction_below_coulomb_friction_is_one_line_naming_the_key():
    with pytest.raises(StationError, match=r"^m: effect 'static_friction' = 5 below coulomb_friction = 8"):
        check_effects({"coulomb_friction": 8.0, "static_friction": 5.0}, "m")
    assert check_effects({"coulomb_friction": 8.0, "static_friction": 8.0})  # equal: plain Coulomb
    assert check_effects({"static_friction": 8.0})  # no sliding level: v_c = 0
    m = load_model().with_effects({"static_friction": 9.0})
    with pytest.raises(StationError, match="static_friction"):
        m.with_effects({"coulomb_friction": 10.0})


def test_friction_levels():
    from station.plant.effects import friction_levels

    assert friction_levels({}) == (0.0, 0.0, 0.05)
    assert friction_levels({"coulomb_friction": 4.0}) == (4.0, 4.0, 0.05)
    assert friction_levels({"static_friction": 9.0, "stribeck_speed": 0.2}) == (0.0, 9.0, 0.2)


def test_viscous_friction_adds_exactly_k_tau_b_to_the_motor_damping():
    m = load_model()
    p = m.with_effects({"viscous_friction": 3.0}).linear_params()
    assert p.J_m == pytest.approx(m.params.J_m, rel=1e-12)
    assert p.c_m == pytest.approx(m.params.c_m + m.params.k_tau * 3.0, rel=1e-12)
    assert p.drive_c == m.params.drive_c and p.k_tau == m.params.k_tau
    # beside a param ratio: the ratio first, then the friction on the scaled motor
    q = m.with_effects({"viscous_friction": 3.0, "param:act_p": 2.0}).linear_params()
    scaled = m.with_effects({"param:act_p": 2.0}).linear_params()
    assert q.c_m == pytest.approx(scaled.c_m + m.params.k_tau * 3.0, rel=1e-12)
    assert q.J_m == pytest.approx(scaled.J_m, rel=1e-12)
    assert not m.with_effects({"viscous_friction": 3.0}).has_plant_effects
    assert not m.with_effects({"amp_offset": 3.0, "stribeck_speed": 0.2}).has_plant_effects
    assert m.with_effects({"static_friction": 3.0}).has_plant_effects


@pytest.mark.parametrize("text", ["", "# a comment only\n"])
def test_an_empty_model_or_parameter_file_is_refused(tmp_path, text):
    """A fuzzing round: a 0-byte --model ran as tmm-fit, silently (and `tune --robust` counted it
    as a model of its set)."""
    path = tmp_path / "m.toml"
    path.write_text(text)
    with pytest.raises(StationError, match="an empty model file"):
        load_model(path)
    with pytest.raises(StationError, match="an empty parameter file"):
        load_params(path)
