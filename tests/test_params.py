import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from impactbeams.params import STRIP_THICKNESS, ParameterError, Params


def test_defaults_are_the_papers_beams():
    p = Params()
    a1, a2 = p.wave_constant
    assert a1 == pytest.approx(0.7, rel=1e-14) and a2 == pytest.approx(0.7, rel=1e-14)
    assert STRIP_THICKNESS == pytest.approx(0.469e-3, rel=1e-3)  # MODEL.md: about 0.469 mm
    assert (p.l1, p.l2, p.clearance, p.force_amplitude, p.omega) == (0.1, 0.12, 1.1e-5, 1e-3, 50)
    assert p.damping_ratio == 0 and p.uplift1 == 0 and p.uplift2 == 0


def test_material_keys_give_strip_stiffness():
    p = Params.from_mapping({"E1": 70e9, "rho1": 2700.0, "width1": 0.01, "thickness1": 1e-3})
    assert p.EI1 == pytest.approx(70e9 * 0.01 * 1e-9 / 12, rel=1e-15)
    assert p.rhoA1 == pytest.approx(2700 * 0.01 * 1e-3, rel=1e-15)
    assert p.EI2 == Params().EI2  # beam 2 untouched


@pytest.mark.parametrize(
    ("changes", "fragment"),
    [
        ({"l1": -0.1}, "l1 = -0.1 is not allowed: must be > 0 (m)"),
        ({"EI2": 0.0}, "EI2 = 0.0 is not allowed: must be > 0 (N m^2)"),
        ({"rhoA1": -1.0}, "rhoA1 = -1.0"),
        ({"clearance": 0.0}, "clearance = 0.0 is not allowed: must be > 0 (m)"),
        ({"clearance": math.nan}, "clearance = nan is not allowed: must be a finite real number"),
        ({"omega": math.inf}, "omega = inf"),
        ({"force_amplitude": -1e-3}, "force_amplitude = -0.001 is not allowed: must be >= 0"),
        ({"damping_ratio": 1.0}, "damping_ratio = 1.0 is not allowed: must satisfy 0 <="),
        ({"uplift2": 2e-5}, "initial gap clearance + uplift1 - uplift2"),
        ({"l2": "0.1"}, "l2 = '0.1' is not allowed: must be a finite real number"),
        ({"thickness2": -1e-3}, "thickness2 = -0.001 is not allowed: must be > 0 (m)"),
    ],
)
def test_bad_values_name_parameter_value_and_rule(changes, fragment):
    with pytest.raises(ParameterError, match=None) as error:
        Params.from_mapping(changes)
    assert fragment in str(error.value)


def test_unknown_and_conflicting_keys():
    with pytest.raises(ParameterError, match="unknown parameter 'clerance'"):
        Params.from_mapping({"clerance": 1e-5})
    with pytest.raises(ParameterError, match="both EI1 and material keys E1"):
        Params.from_mapping({"EI1": 1.0, "E1": 1e9})


def test_toml_file(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("[params]\nclearance = 2e-5\nomega = 40\nthickness2 = 5e-4\n")
    p = Params.from_toml(path)
    assert (p.clearance, p.omega) == (2e-5, 40.0)
    assert p.rhoA2 == pytest.approx(7850 * 5e-3 * 5e-4, rel=1e-15)
    path.write_text("[params]\nforce = 1e-3\n")
    with pytest.raises(ParameterError, match="unknown parameter 'force' in \\[params\\] of"):
        Params.from_toml(path)
    path.write_text("[params\n")
    with pytest.raises(ParameterError, match="is not valid TOML"):
        Params.from_toml(path)
    with pytest.raises(ParameterError, match="does not exist"):
        Params.from_toml(tmp_path / "missing.toml")


def test_replace_with_material_key_drops_direct_stiffness():
    p = Params(EI1=1.0).replace(thickness1=1e-3)
    assert p.EI1 == pytest.approx(210e9 * 5e-3 * 1e-9 / 12, rel=1e-15)


@settings(max_examples=50, deadline=None, derandomize=True, database=None)
@given(clearance=st.floats(1e-12, 1e-2), uplift1=st.floats(-1e-3, 1e-3),
       zeta=st.floats(0, 0.99))
def test_valid_values_round_trip(clearance, uplift1, zeta):
    if clearance + uplift1 <= 0:
        with pytest.raises(ParameterError):
            Params(clearance=clearance, uplift1=uplift1)
        return
    p = Params(clearance=clearance, uplift1=uplift1, damping_ratio=zeta)
    assert Params.from_mapping(p.as_dict()) == p


def test_material_keys_work_as_keywords():
    """Params(width1=...) is Params.from_mapping({"width1": ...}) (was a bare TypeError)."""
    keywords = {"E1": 70e9, "rho1": 2700.0, "width1": 0.02, "thickness2": 6e-4}
    assert Params(**keywords) == Params.from_mapping(keywords)
    assert Params(width1=0.02).EI1 == pytest.approx(210e9 * 0.02 * STRIP_THICKNESS**3 / 12,
                                                    rel=1e-15)
    with pytest.raises(ParameterError, match="both EI1 and material keys width1"):
        Params(EI1=1.0, width1=0.02)
    with pytest.raises(ParameterError, match="width2 in Params\\(\\) is not allowed: "
                                             "counterpart = 'stop' has no beam 2"):
        Params(counterpart="stop", width2=0.01)


@pytest.mark.parametrize(("key", "suggestion"), [
    ("clearence", "clearance"), ("Clearance", "clearance"), ("force", "force_amplitude"),
    ("dampingratio", "damping_ratio"), ("omgea", "omega")])
def test_an_unknown_keyword_names_the_nearest_and_the_allowed(key, suggestion):
    with pytest.raises(ParameterError) as error:
        Params(**{key: 1e-5})
    message = str(error.value)
    assert message.startswith(f"unknown parameter {key!r} in Params() (did you mean "
                              f"{suggestion!r}?); allowed: E1, E2, EI1, EI2, base_amplitude, "
                              "clearance,")
    assert not isinstance(error.value, TypeError)


def test_an_unknown_key_far_from_every_name_gets_no_suggestion():
    with pytest.raises(ParameterError, match=r"unknown parameter 'xyzzy' in Params\(\); allowed"):
        Params(xyzzy=1.0)
