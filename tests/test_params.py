"""Parameter sets: loading, validation messages, drag rules and Froude scaling."""

import json
import math

import numpy as np
import pytest

from sim import params


def test_both_presets_load_and_build():
    assert params.available_presets() == ["full-scale", "model-scale"]
    full = params.load("full-scale")
    model = params.load("model-scale")
    assert full.tree.mass_kg == 36000.0
    assert model.rov.name == "Minerva"
    for ps in (full, model):
        for m in (ps.tree.M_rb + ps.tree.M_a, ps.rov.M_rb + ps.rov.M_a):
            np.testing.assert_allclose(m, m.T)
            assert np.linalg.eigvalsh(m).min() > 0  # symmetric positive definite


def test_drag_rules_reproduce_the_thesis_model_scale_surge_values():
    """The rules of section 2.3.4 applied to the module's box give B.7/B.8's surge entries
    (695.7 and 158.6, printed to 0.1 -> 0.05 % tolerance)."""
    d_l, d_nl = params.tree_drag_coefficients(1.0, 1.5, 1.2, 336.4)
    assert d_nl[0] == pytest.approx(695.7, rel=5e-4)
    assert d_l[0] == pytest.approx(158.6, rel=5e-4)
    # sway is 1.8 times surge in coefficient, over the side face (L H instead of W H)
    assert d_nl[1] / d_nl[0] == pytest.approx(1.8 * (1.0 * 1.2) / (1.5 * 1.2))
    # strip theory: one face pair of the yaw value equals rho C_d H L^4 / 64, the thesis's 19.2
    assert 1025 * 1.2 * 1.0**4 / 64 == pytest.approx(19.2, abs=0.05)
    assert d_nl[5] == pytest.approx(1025 * 1.2 * (1.0**4 + 1.5**4) / 64)


def test_full_scale_heave_damping_is_one_percent_of_critical_at_400_m():
    full = params.load("full-scale")
    k = full.wire.axial_stiffness_newton / 400.0
    critical = 2 * math.sqrt(k * (full.tree.M_rb[2, 2] + full.tree.M_a[2, 2]))
    assert full.tree.D_l[2] == pytest.approx(0.01 * critical)


def test_unknown_preset_names_the_choices():
    with pytest.raises(params.ParameterError, match="unknown parameter set 'deep'.*full-scale"):
        params.load("deep")


def _preset_dict(name):
    return params.load_spec(name).model_dump()


def test_out_of_range_value_names_the_field_and_range(tmp_path):
    data = _preset_dict("model-scale")
    data["rov"]["buoyancy_ratio"] = 1.5
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    with pytest.raises(params.ParameterError) as err:
        params.load(path)
    text = str(err.value)
    assert "rov.buoyancy_ratio" in text and "less than or equal to 1.1" in text
    assert str(path) in text


def test_missing_field_and_nan_are_named():
    data = _preset_dict("full-scale")
    del data["tree"]["attachment_height_m"]
    data["gains"]["kp"][1] = float("nan")
    with pytest.raises(params.ParameterError) as err:
        params.parse_spec(data, "test")
    text = str(err.value)
    assert "tree.attachment_height_m: Field required" in text
    assert "gains.kp.1" in text


def test_asymmetric_mass_matrix_is_refused():
    data = _preset_dict("full-scale")
    data["rov"]["added_mass"][1][0] = -68.773  # the OCR slip of B.13
    with pytest.raises(params.ParameterError, match="rov.added_mass.*must be symmetric"):
        params.parse_spec(data)


def test_thruster_lists_must_agree():
    data = _preset_dict("model-scale")
    data["rov"]["thrusters"]["k_neg"] = data["rov"]["thrusters"]["k_neg"][:3]
    with pytest.raises(params.ParameterError, match="k_neg must have one entry per thruster"):
        params.parse_spec(data)


def test_unknown_field_is_refused():
    data = _preset_dict("model-scale")
    data["tree"]["colour"] = "yellow"
    with pytest.raises(params.ParameterError, match="tree.colour: Extra inputs"):
        params.parse_spec(data)


def test_froude_scaling_round_trip_and_laws():
    spec = params.load_spec("full-scale")
    lam = 1 / 3.5
    small = params.froude_scale(spec, lam)
    back = params.froude_scale(small, 1 / lam)
    np.testing.assert_allclose(
        back.tree.rigid_body_inertia, spec.tree.rigid_body_inertia, rtol=1e-12
    )
    np.testing.assert_allclose(back.tree.added_mass, spec.tree.added_mass, rtol=1e-12)
    assert back.tree.length_m == pytest.approx(spec.tree.length_m)
    assert small.tree.mass_kg == pytest.approx(36000 * lam**3)
    assert small.tree.rigid_body_inertia[5] == pytest.approx(58942 * lam**5)
    # a Froude-scaled tree of 1/3.5 is about the sea-trial module's size (thesis 2.3.5)
    assert small.tree.height_m == pytest.approx(0.80, abs=0.01)
    with pytest.raises(params.ParameterError, match=r"scale must be in \(0, 10\]"):
        params.froude_scale(spec, -1.0)


def test_froude_scaled_damping_keeps_the_dimensionless_drag():
    """Linear damping scales with lambda^2.5, quadratic with lambda^2: the drag force at the
    Froude-scaled speed is lambda^3 of the full-scale force."""
    spec = params.load_spec("model-scale")
    lam = 3.5
    big = params.froude_scale(spec, lam)
    u = 0.1
    f_small = spec.tree.linear_damping[0] * u + spec.tree.quadratic_damping[0] * u**2
    u_big = u * math.sqrt(lam)
    f_big = big.tree.linear_damping[0] * u_big + big.tree.quadratic_damping[0] * u_big**2
    assert f_big == pytest.approx(f_small * lam**3)


def test_files_with_the_old_newton_spelling_still_load(tmp_path):
    """Parameter files written before newtons were spelt `_newton` keep working, with the same
    numbers; giving both spellings is refused as an extra field."""
    data = _preset_dict("model-scale")
    data["tree"]["submerged_weight_n"] = data["tree"].pop("submerged_weight_newton")
    data["wire"]["axial_stiffness_n"] = data["wire"].pop("axial_stiffness_newton")
    path = tmp_path / "old.json"
    path.write_text(json.dumps(data))
    old = params.load(path)
    new = params.load("model-scale")
    assert old.tree.submerged_weight_newton == new.tree.submerged_weight_newton == 7848.0
    assert old.spec.wire.axial_stiffness_newton == new.spec.wire.axial_stiffness_newton
    data["tree"]["submerged_weight_newton"] = 1.0
    path.write_text(json.dumps(data))
    with pytest.raises(params.ParameterError, match="submerged_weight_n"):
        params.load(path)


def test_a_parameter_file_edited_between_loads_is_read_again(tmp_path):
    """``load_spec`` keeps parsed files by their text (a campaign loads its set for every
    run): the same text gives the same (frozen) spec, an edited file its new values, and a
    file broken by the edit its parse error, naming the file."""
    path = tmp_path / "rig.toml"
    text = (params.PRESET_DIR / "full-scale.toml").read_text()
    path.write_text(text)
    first = params.load_spec(path)
    assert params.load_spec(path) is first
    mass = first.tree.mass_kg
    edited = text.replace(f"mass_kg = {mass!r}", f"mass_kg = {mass + 1000.0!r}", 1)
    assert edited != text
    path.write_text(edited)
    assert params.load_spec(path).tree.mass_kg == mass + 1000.0
    path.write_text(text + "\n[[[ broken")
    with pytest.raises(params.ParameterError, match=r"cannot parse .*rig\.toml"):
        params.load_spec(path)
