"""Calibration files: the shipped stations load; every field is validated with a one-line error."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import pytest
import yaml

from ur3hanoi.errors import CalibrationError
from ur3hanoi.station import Station, load_station, parse_station, station_to_dict

from .conftest import LAB_REAL, LAB_SIM


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
]


@pytest.mark.parametrize(("field", "value", "match"), BAD_FIELDS, ids=[f"{f}={v!r}" for f, v, _ in BAD_FIELDS])
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
    with pytest.raises(CalibrationError, match="readable calibration file"):
        load_station(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("grid: [unclosed\n")
    with pytest.raises(CalibrationError, match="valid YAML"):
        load_station(bad)
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(CalibrationError, match="mapping"):
        load_station(bad)


def test_stations_are_frozen(lab_sim: Station) -> None:
    with pytest.raises(AttributeError):
        lab_sim.approach = 0.2  # type: ignore[misc]
