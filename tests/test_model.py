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
    named = {"coulomb_friction", "deadzone", "saturation", "delay", "backlash", "beam_damping", "accel_gain"}
    params = {"mu", "EI", "drive_k", "drive_c", "clamp_k", "clamp_c", "J_base", "m_accel", "J_accel", "act_K",
              "act_p"}
    assert set(EFFECTS) == named | {f"param:{p}" for p in params}
    assert set(CANDIDATES) == named | {f"param:{p}" for p in params} and len(CANDIDATES) == 18
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
