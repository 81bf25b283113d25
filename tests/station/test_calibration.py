"""Calibration files: the shipped stations load; every field is validated with a one-line error."""

from __future__ import annotations

import copy
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from tests.conftest import LAB_REAL, LAB_SIM
from ur3hanoi.errors import CalibrationError
from ur3hanoi.station.calibration import Station, load_station, parse_station, station_to_dict, with_suction_profile
from ur3hanoi.station.suction_profile import LAB_SIM as SIM_LEVELS
from ur3hanoi.station.suction_profile import REAL


def _raw(path: Path) -> dict[str, Any]:
    return yaml.safe_load(path.read_text())


def test_lab_sim_values(lab_sim: Station) -> None:
    assert lab_sim.layout == "flat"
    assert lab_sim.base_xyz == pytest.approx((-0.15, 0.15, 0.01))
    assert lab_sim.tool.parent == "ee_link"
    assert lab_sim.tool.xyz == pytest.approx((0.059, 0.0535, 0.0))
    assert lab_sim.tool.rpy == pytest.approx((0.0, math.pi / 2, 0.0), abs=1e-15)
    assert lab_sim.tool_yaw == pytest.approx(math.pi / 2)
    assert lab_sim.q_home == pytest.approx(tuple(math.radians(d) for d in (120, -90, 90, -90, -90, 0)))
    assert [o[1] for o in lab_sim.tower_origins] == pytest.approx([0.05, 0.15, 0.25])
    assert lab_sim.approach == pytest.approx(0.096)
    assert len(lab_sim.sha256) == 64


def test_lab_real_is_stacked_with_explicit_towers(lab_real: Station) -> None:
    assert lab_real.layout == "stacked"
    assert lab_real.n_towers == 3
    assert lab_real.height_step == pytest.approx((0.0, 0.0, 0.0318))
    assert lab_real.contact_depth == pytest.approx(0.003)


def test_origin_step_and_explicit_forms_agree() -> None:
    raw = _raw(LAB_SIM)
    explicit = copy.deepcopy(raw)
    g = explicit["grid"]
    g["tower_origins"] = [[0.40, 0.05 + 0.10 * t, 0.0125] for t in range(3)]
    del g["origin"], g["tower_step"]
    a, b = parse_station(raw, "a.yaml"), parse_station(explicit, "b.yaml")
    for p, q in zip(a.tower_origins, b.tower_origins, strict=True):
        assert p == pytest.approx(q, abs=1e-12)


def test_round_trip_through_station_to_dict(shipped_station: Station) -> None:
    again = parse_station(station_to_dict(shipped_station), "again.yaml")
    for p, q in zip(again.tower_origins, shipped_station.tower_origins, strict=True):
        assert p == pytest.approx(q, abs=1e-12)
    assert again.q_home == pytest.approx(shipped_station.q_home, abs=1e-12)
    assert again.tool == shipped_station.tool or again.tool.rpy == pytest.approx(shipped_station.tool.rpy)
    assert again.suction == shipped_station.suction


def _mutated(path: Path, dotted: str, value: Any) -> dict[str, Any]:
    raw = _raw(path)
    node = raw
    *parents, last = dotted.split(".")
    for p in parents:
        node = node[p]
    if value is _DELETE:
        del node[last]
    else:
        node[last] = value
    return raw


_DELETE = object()

BAD_FIELDS = [
    ("layout", "stacky", "layout"),
    ("robot.base_xyz", _DELETE, "robot.base_xyz"),
    ("robot.base_xyz", [0.0, 0.0], "robot.base_xyz"),
    ("robot.base_xyz", [0.0, float("nan"), 0.0], r"robot.base_xyz\[1\]"),
    ("robot.home_deg", [0, 0, 0, 0, 0], "robot.home_deg"),
    ("robot.home_deg", [0, 0, 400, 0, 0, 0], "robot.home_deg"),
    ("robot.elbow_limit_deg", -10, "robot.elbow_limit_deg"),
    ("tool.parent", "wrist_3_link", "tool.parent"),
    ("tool.xyz", "0.059 0.0535 0", "tool.xyz"),
    ("tool.yaw_deg", "ninety", "tool.yaw_deg"),
    ("blocks.size", -0.0318, "blocks.size"),
    ("blocks.size", 0, "blocks.size"),
    ("blocks.contact_depth", 0.05, "blocks.contact_depth"),
    ("grid.towers", 1, "grid.towers"),
    ("grid.towers", 2.5, "grid.towers"),
    ("grid.heights", 0, "grid.heights"),
    ("grid.height_step", [-0.10, 0.0, 0.01], "grid.height_step"),
    ("grid.height_step", [-0.01, 0.0, 0.0], "grid.height_step"),
    ("grid.tower_step", [0.0, 0.01, 0.0], "grid.tower_origins"),
    ("grid.approach", -0.1, "grid.approach"),
    ("grid.approach", float("inf"), "grid.approach"),
    ("suction", {"profile": "vacuum"}, "suction.profile"),
    ("suction", {"ain0_held": 12.0}, "suction.ain0_held"),
    ("suction", {"ain0_noise": -0.01}, "suction.ain0_noise"),
    ("suction", {"digin_held": 1.5}, "suction.digin_held"),
    ("suction", {"digin_free": True}, "suction.digin_free"),
    ("suction", "real", "suction"),
]


_IDS = [f"{f}=<deleted>" if v is _DELETE else f"{f}={v!r}" for f, v, _ in BAD_FIELDS]  # the same in every process


@pytest.mark.parametrize(("field", "value", "match"), BAD_FIELDS, ids=_IDS)
def test_bad_field_names_file_field_value_and_range(field: str, value: Any, match: str) -> None:
    with pytest.raises(CalibrationError, match=match) as info:
        parse_station(_mutated(LAB_SIM, field, value), "bad.yaml")
    msg = str(info.value)
    assert msg.startswith("bad.yaml: field ")
    assert "expected" in msg
    assert "\n" not in msg


def test_stacked_height_step_must_be_one_block() -> None:
    with pytest.raises(CalibrationError, match=r"grid\.height_step.*stacked"):
        parse_station(_mutated(LAB_REAL, "grid.height_step", [0.0, 0.0, 0.05]), "bad.yaml")


def test_overlapping_towers_are_numbered_from_1() -> None:
    origins = [[0.25, -0.20, 0.0288], [0.25, -0.09, 0.0288], [0.25, -0.08, 0.0288]]
    with pytest.raises(CalibrationError, match=r"expected towers 2 and 3 at least blocks.size = 0.0318 m apart"):
        parse_station(_mutated(LAB_REAL, "grid.tower_origins", origins), "bad.yaml")


def test_tower_origins_count_must_match() -> None:
    with pytest.raises(CalibrationError, match=r"grid\.tower_origins"):
        parse_station(_mutated(LAB_REAL, "grid.towers", 4), "bad.yaml")


def test_both_tower_forms_is_an_error() -> None:
    raw = _mutated(LAB_REAL, "grid.origin", [0.3, 0.0, 0.03])
    with pytest.raises(CalibrationError, match=r"grid\.origin"):
        parse_station(raw, "bad.yaml")


def test_degrees_and_radians_both_given_is_an_error() -> None:
    raw = _mutated(LAB_SIM, "robot.home_rad", [0.0] * 6)
    with pytest.raises(CalibrationError, match=r"robot\.home_rad"):
        parse_station(raw, "bad.yaml")


def test_radians_form_is_accepted() -> None:
    raw = _raw(LAB_SIM)
    del raw["robot"]["home_deg"]
    raw["robot"]["home_rad"] = [2.0943951023931953, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0]
    assert parse_station(raw).q_home[0] == pytest.approx(math.radians(120))


def test_file_errors(tmp_path: Path) -> None:
    with pytest.raises(CalibrationError, match=r"missing.yaml: cannot read the calibration file \(No such file or "
                                               r"directory\); shipped stations: lab_real, lab_sim"):
        load_station(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("grid: [unclosed\n")
    with pytest.raises(CalibrationError, match=r"bad.yaml: not valid YAML: .*\(line 2, column 1\)"):
        load_station(bad)
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(CalibrationError, match=r"expected a mapping with keys name, layout, robot, .*, got a list"):
        load_station(bad)
    bad.write_text("")
    with pytest.raises(CalibrationError, match="got an empty document"):
        load_station(bad)


def _dump(raw: dict[str, Any]) -> str:
    return yaml.safe_dump(raw, sort_keys=False)


def test_typo_base_rpy_is_an_error_with_the_suggestion(tmp_path: Path) -> None:
    # The typo that silently produced an unrotated table: `base_rpy` instead of `base_rpy_deg`.
    raw = _raw(LAB_SIM)
    del raw["robot"]["base_rpy_deg"]
    raw["robot"]["base_rpy"] = [0, 0, 10]
    path = tmp_path / "typo.yaml"
    path.write_text(_dump(raw))
    with pytest.raises(CalibrationError) as info:
        load_station(path)
    assert str(info.value) == (f"{path}: field 'robot.base_rpy' is unknown: did you mean 'robot.base_rpy_deg'?")
    # Spelled right, the rotation is used: the station's base pose differs from the unrotated one.
    raw["robot"]["base_rpy_deg"] = raw["robot"].pop("base_rpy")
    rotated = parse_station(raw, "ok.yaml")
    assert rotated.base_rpy[2] == pytest.approx(math.radians(10))
    assert not np.allclose(rotated.T_world_base.rotation, load_station(LAB_SIM).T_world_base.rotation)


@pytest.mark.parametrize(
    ("dotted", "value", "message"),
    [
        ("grids", {}, "field 'grids' is unknown: did you mean 'grid'?"),
        ("colour", "red",
         "field 'colour' is unknown: expected one of name, layout, robot, tool, blocks, grid, suction, io"),
        ("tool.yaw", 90, "field 'tool.yaw' is unknown: did you mean 'tool.yaw_deg'?"),
        ("grid.tower_orgins", [[0, 0, 0]] * 3, "field 'grid.tower_orgins' is unknown: did you mean "
                                               "'grid.tower_origins'?"),
        ("robot.home", [0] * 6, "field 'robot.home' is unknown: did you mean 'robot.home_deg'?"),
    ],
)
def test_unknown_keys_are_errors_naming_the_nearest_valid_one(dotted: str, value: Any, message: str) -> None:
    raw = _mutated(LAB_SIM, dotted, value)
    with pytest.raises(CalibrationError) as info:
        parse_station(raw, "bad.yaml")
    assert str(info.value) == f"bad.yaml: {message}"


def test_duplicate_key_is_an_error(tmp_path: Path) -> None:
    text = LAB_SIM.read_text()
    path = tmp_path / "dup.yaml"
    path.write_text(text.replace("  approach: 0.096", "  approach: 0.096\n  'approach': 0.05"))
    with pytest.raises(CalibrationError, match=r"dup.yaml: not valid YAML: duplicate key 'approach' \(first given "
                                               r"on line \d+\) \(line \d+, column 3\)"):
        load_station(path)


@pytest.mark.parametrize(
    ("dotted", "value", "match"),
    [
        ("grid.towers", "3", r"field 'grid.towers' = '3' is invalid: expected an integer in \[2, 10\]"),
        ("blocks.size", True, r"field 'blocks.size' = True is invalid: expected a length \[m\] in \(0, 0.2\]"),
        ("grid.approach", 10**400, r"field 'grid.approach' = 1000.*000 is invalid: expected a length"),
        ("grid.heights", 10**400, r"field 'grid.heights' = 1000.*000 is invalid: expected an integer in \[1, 20\]"),
        ("robot.base_xyz", [0, float("-inf"), 0], r"field 'robot.base_xyz\[1\]' = -inf is invalid"),
        ("name", "two\nlines", r"field 'name' = 'two\\nlines' is invalid: expected a non-empty single-line"),
        ("name", "x" * 5000, r"field 'name' = 'x{20,40}\.\.\.x{20,40}' is invalid"),
        ("layout", ["flat"] * 10000, r"field 'layout' = \['flat', 'flat', .*\.\.\.\] is invalid"),
    ],
    ids=["string-int", "bool", "huge-float", "huge-int", "inf", "newline-name", "long-name", "long-list"],
)
def test_wrong_types_and_huge_values_name_file_field_value_and_range(dotted: str, value: Any, match: str) -> None:
    with pytest.raises(CalibrationError, match=match) as info:
        parse_station(_mutated(LAB_SIM, dotted, value), "bad.yaml")
    assert len(str(info.value)) < 250 and "\n" not in str(info.value)


def test_stations_are_frozen(lab_sim: Station) -> None:
    with pytest.raises(AttributeError):
        lab_sim.approach = 0.2  # type: ignore[misc]


def test_suction_section_selects_a_profile_or_explicit_levels(lab_sim: Station, lab_real: Station) -> None:
    """No section: the course simulator's levels; `profile: real`; explicit levels over a profile make `custom`."""
    assert lab_sim.suction == SIM_LEVELS
    assert lab_real.suction == REAL  # the shipped real-station example uses the `real` profile
    assert parse_station(_mutated(LAB_SIM, "suction", {"profile": "real"}), "x.yaml").suction == REAL
    custom = parse_station(_mutated(LAB_SIM, "suction", {"profile": "real", "ain0_held": 2.6, "digin_held": 3}),
                           "x.yaml").suction
    assert (custom.name, custom.ain0_held, custom.digin_held, custom.ain0_free) == ("custom", 2.6, 3, REAL.ain0_free)
    # A custom profile survives the calibration round trip (calibrate writes it back).
    again = parse_station(station_to_dict(replace(lab_sim, suction=custom)), "again.yaml")
    assert again.suction == custom
    assert with_suction_profile(lab_sim, "real").suction == REAL
    with pytest.raises(CalibrationError, match="suction profile 'x' is unknown: expected one of lab_sim, real"):
        with_suction_profile(lab_sim, "x")
