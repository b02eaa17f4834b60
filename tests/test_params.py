"""Parameter sets: shipped values, file loading, and refusal of non-physical descriptions."""

from __future__ import annotations

from importlib import resources

import pytest
import yaml

from biped_gait.core.model.biped import BipedModel
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.model.params import load_params, names_set, params_from_dict, shipped_param_names
from biped_gait.core.model.yaml_files import parse_package_yaml, parse_yaml

pytestmark = pytest.mark.core


@pytest.mark.parametrize("name", ["aoustin2013", "aoustin2013-table"])
def test_total_mass_is_the_tables(name):
    params = load_params(name)
    assert params.total_mass == pytest.approx(52.1, abs=1e-12)
    assert BipedModel.from_params(params).total_mass == pytest.approx(52.1, abs=1e-12)


def test_default_set_corrects_only_the_arm_inertia():
    default, table = load_params(None), load_params("aoustin2013-table")
    assert default.name == "aoustin2013"
    assert default.arm.inertia[0] == pytest.approx(4.6 * 0.66**2 / 12, abs=1e-4)
    assert table.arm.inertia == (0.7414, 0.7414, 0.0)
    for link in ("shin", "thigh", "trunk"):
        assert getattr(default, link) == getattr(table, link)
    assert shipped_param_names() == ["aoustin2013", "aoustin2013-hips", "aoustin2013-table"]


def test_the_hips_set_is_the_default_with_hip_joints():
    """aoustin2013-hips: the default's links and geometry, the legs given an axial inertia, and a
    yaw, a roll and a pitch joint in each hip."""
    default, hips = load_params("aoustin2013"), load_params("aoustin2013-hips")
    assert hips.trunk == default.trunk and hips.arm == default.arm and hips.hip_half_width == default.hip_half_width
    for link in ("shin", "thigh"):
        a, b = getattr(default, link), getattr(hips, link)
        assert (a.length, a.mass, a.com_offset, a.inertia[:2]) == (b.length, b.mass, b.com_offset, b.inertia[:2])
        assert a.inertia[2] == 0.0 < b.inertia[2]
    assert hips.joints.hip_roles == ("hip_yaw", "hip_roll", "hip_pitch") and hips.joints.lateral_hips
    assert default.joints.hip_roles == ("hip_pitch",) and not default.joints.lateral_hips


def _edited(tmp_path, edit) -> str:
    raw = yaml.safe_load(resources.files("biped_gait.core.data").joinpath("aoustin2013.yaml").read_text())
    edit(raw)
    path = tmp_path / "edited.yaml"
    path.write_text(yaml.safe_dump(raw))
    return str(path)


def test_a_copied_file_loads(tmp_path):
    path = _edited(tmp_path, lambda raw: raw["links"]["arm"].update(mass=5.0))
    assert load_params(path).arm.mass == 5.0


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda raw: raw["links"]["thigh"].pop("mass"), "missing value mass"),
        (lambda raw: raw["links"].pop("arm"), "missing value links.arm"),
        (lambda raw: raw["links"]["shin"].update(mass=-4.6), "mass must be positive"),
        (lambda raw: raw["links"]["trunk"].update(inertia=[11.3, -1.0, 11.3]), "is not physical"),
        (lambda raw: raw["links"]["arm"].update(inertia=[0.1, 0.1, 0.5]), "is not physical"),
        (lambda raw: raw["links"]["arm"].update(length=float("nan")), "must be finite"),
        (lambda raw: raw["geometry"].update(hip_half_width=0.0), "must be positive"),
        (lambda raw: raw["links"]["shin"].update(com_offset=0.6), "com_offset must lie in"),
        (lambda raw: raw["joints"][2].update(role="hip_twist"), "unknown role 'hip_twist'"),
        (lambda raw: raw["joints"][3].update(axis="x"), "a knee joint turns about y, not 'x'"),
        (lambda raw: raw["joints"][4].update(name="{side}_torso"), "the torso's joint has no {side}"),
        (lambda raw: raw["joints"].pop(5), "no shoulder joint"),
        (lambda raw: raw["joints"].append(dict(raw["joints"][3])), "role knee appears 2 times"),
        (lambda raw: raw["joints"][3].update(parent="pelvis"), "must hang on thigh"),
        (lambda raw: raw["joints"][2].update(upper=-3.0), "lower < upper"),
        (lambda raw: raw["joints"].insert(3, {"name": "{side}_hip_roll", "role": "hip_roll", "axis": "x",
                                              "parent": "pelvis", "child": "hip_link"}),
         "a pitch joint alone, or a pitch, a roll and a yaw joint"),
    ],
)
def test_non_physical_files_are_refused(tmp_path, edit, message):
    with pytest.raises(ValueError, match=message):
        load_params(_edited(tmp_path, edit))


def test_a_file_set_is_named_by_its_path_or_its_name_never_by_another_set(tmp_path):
    """``names_set``: the file's set is named by nothing, its path (or another path to the same
    file) and its name; a shipped name names the shipped set, also where the file took that name
    with other values; another file is never read. The planner of the file plans for it named
    any of these ways (the tutorial's section 7)."""
    path = _edited(tmp_path, lambda raw: raw.update(name="my-biped") or raw["links"]["arm"].update(mass=3.0))
    mine = load_params(path)
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "copy").mkdir()
    other = _edited(tmp_path / "elsewhere", lambda raw: raw.update(name="my-biped"))
    for given in ("", path, "my-biped", str(tmp_path / "." / "edited.yaml")):
        assert names_set(given, mine, path), given
    for given in ("aoustin2013", other, "your-biped", str(tmp_path / "missing.yaml")):
        assert not names_set(given, mine, path), given
    copied = _edited(tmp_path / "copy", lambda raw: raw["links"]["arm"].update(mass=3.0))  # named aoustin2013 still
    assert not names_set("aoustin2013", load_params(copied), copied) and names_set(copied, load_params(copied), copied)
    assert names_set("aoustin2013", load_params(), None) and names_set("aoustin2013", load_params(), "aoustin2013")
    planner = GaitPlanner(path, atlas=False)
    gaits = [planner.plan(GaitRequest(0.45, 0.45, 0.41, params=given)) for given in ("", path, "my-biped")]
    assert all(g.params == "my-biped" and g.W == gaits[0].W for g in gaits)
    with pytest.raises(ValueError, match="holds parameter set 'my-biped'"):
        planner.plan(GaitRequest(0.45, 0.45, 0.41, params="aoustin2013"))


def test_unknown_name_is_refused():
    with pytest.raises(ValueError, match="unknown parameter set 'nope'"):
        load_params("nope")


@pytest.mark.parametrize("name", shipped_param_names())
def test_a_shipped_set_reads_the_same_by_libyaml_as_by_the_checked_parser(name):
    text = resources.files("biped_gait.core.data").joinpath(f"{name}.yaml").read_text()
    assert parse_package_yaml(text) == parse_yaml(text, name)
    assert load_params(name) == params_from_dict(parse_yaml(text, name), name)
