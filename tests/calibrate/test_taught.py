"""Taught-points files and tables used as taught points: strict schema, unit mix-ups, radians out."""

from __future__ import annotations

import dataclasses
import hashlib
import math
from pathlib import Path

import pytest
import yaml

from tests.conftest import REPO
from ur3hanoi.calibrate.taught import load_taught, parse_taught, taught_from_table, taught_text
from ur3hanoi.errors import TableError, TaughtPointsError
from ur3hanoi.io.resources import TAUGHT_EXAMPLE, stations_dir
from ur3hanoi.station.grid import ABOVE, ON

HOME_DEG = [120, -90, 90, -90, -90, 0]


def test_load_taught_converts_degrees(tmp_path: Path) -> None:
    f = tmp_path / "t.yaml"
    f.write_text("units: deg\npoints:\n- {tower: 1, height: 2, pose: above, q: [120, -90, 90, -90, -90, 0]}\n")
    taught = load_taught(f)
    (p,) = taught.points
    # Numbered from 1 in the file, 0-based indices in code.
    assert (p.tower, p.height, p.k) == (0, 1, ABOVE)
    assert p.label == "points[0] (tower 1 height 2 above)"
    assert p.q == pytest.approx([math.radians(v) for v in HOME_DEG], abs=1e-15)
    assert taught.sha256 == hashlib.sha256(f.read_bytes()).hexdigest()


def test_taught_text_reads_back_with_its_station_and_above_poses() -> None:
    taught = parse_taught(yaml.safe_load("units: deg\npoints:\n- {tower: 2, height: 1, q: [110.87, -64.65, 136.28, "
                                         "-161.63, -90, 20.87]}\n- {tower: 3, height: 2, pose: above, q: [157.43, "
                                         "-118.07, 141.68, -113.6, -90, 67.43]}\n"))
    assert taught.station == "" and taught.units == "deg"
    text = taught_text(taught.points, 'my "station"', ["a comment"])
    assert text.startswith("# a comment\nunits: deg\n")
    back = parse_taught(yaml.safe_load(text))
    assert back.station == 'my "station"'
    assert [(p.tower, p.height, p.k) for p in back.points] == [(1, 0, ON), (2, 1, ABOVE)]
    for a, b in zip(back.points, taught.points, strict=True):
        assert a.q == pytest.approx(b.q, abs=1e-15)
    tiny = taught_text([dataclasses.replace(back.points[0], q=(-1e-9,) * 6)], "s")
    assert "q: [0.0000, 0.0000" in tiny and "-0.0000" not in tiny


def test_shipped_example_loads() -> None:
    taught = load_taught(stations_dir() / TAUGHT_EXAMPLE)
    assert len(taught.points) == 5
    assert [p.k for p in taught.points] == [ON, ON, ON, ON, ABOVE]


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"units": "deg", "point": []}, "field 'point' is unknown: did you mean 'points'?"),
        ({"units": "deg", "points": [{"tower": 1, "height": 1, "q": HOME_DEG, "pose": "on", "tilt": 0}]},
         "field 'points[0].tilt' is unknown: expected one of points[0].tower, points[0].height, points[0].pose, "
         "points[0].q"),
        ({"units": "deg", "points": [{"tower": 1, "height": 1}]},
         "field 'points[0].q' is missing: expected a list of 6 numbers, each a joint value (in 'units') in "
         "[-360, 360]"),
        ({"units": "deg", "points": [{"tower": 0, "height": 1, "q": HOME_DEG}]},
         "field 'points[0].tower' = 0 is invalid: expected a tower number (numbering starts at 1) in [1, 10]"),
        ({"units": "deg", "points": [{"tower": 1, "height": 0, "q": HOME_DEG}]},
         "field 'points[0].height' = 0 is invalid: expected a height (numbering starts at 1: 1 = bottom) in [1, 20]"),
        ({"units": "deg", "points": [{"tower": 1, "height": 1, "q": [*HOME_DEG[:5], float("nan")]}]},
         "field 'points[0].q[5]' = nan is invalid"),
        ({"units": "deg", "points": []}, "field 'points' = [] is invalid: expected a list of 1..1000 points"),
        ({"units": "rad", "points": [{"tower": 1, "height": 1, "q": HOME_DEG}]},
         "points[0] (tower 1 height 1 on): joint value 120 is outside +-2pi with units rad: looks like degrees"),
    ],
    ids=["typo-points", "unknown-point-key", "missing-q", "zero-tower", "zero-height", "nan", "empty",
         "degrees-as-rad"],
)
def test_invalid_taught_points_name_file_and_field(data: object, message: str) -> None:
    with pytest.raises(TaughtPointsError) as info:
        parse_taught(data, "t.yaml")
    assert str(info.value).startswith(f"t.yaml: {message}")


def test_taught_from_table_uses_every_entry() -> None:
    taught = taught_from_table(REPO / "tables/lab2_data.yaml", "real_pos")
    assert len(taught.points) == 18
    assert [(p.tower, p.height, p.k) for p in taught.points[:3]] == [(0, 0, ON), (0, 0, ABOVE), (0, 1, ON)]
    assert taught.points[2].label == "real_pos[0][1][0] (tower 1 height 2 on)"
    assert taught.shape == (3, 3) and taught.missing == ()


def test_taught_from_table_keeps_what_is_present(tmp_path: Path) -> None:
    on, above = [2.1, -1.2, 1.8, -2.2, -1.57, 0.5], [2.1, -1.4, 1.6, -1.8, -1.57, 0.5]
    path = tmp_path / "t.yaml"
    path.write_text(yaml.safe_dump({"real_pos": [[[on, above], [on, above]], [[on], [on, None]]]}))
    taught = taught_from_table(path, "real_pos")
    assert [p.where for p in taught.points] == ["real_pos[0][0][0]", "real_pos[0][0][1]", "real_pos[0][1][0]",
                                                "real_pos[0][1][1]", "real_pos[1][0][0]", "real_pos[1][1][0]"]
    assert taught.missing == ((1, 0, ABOVE), (1, 1, ABOVE))
    # Tower 1's two above poses are the same values: one pose shared by both heights.
    assert [p.shared for p in taught.points] == [(), (0, 1), (), (0, 1), (), ()]


def test_taught_from_table_refuses_a_degree_table(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text("real_pos: [[[[120, -90, 90, -90, -90, 0], [120, -90, 90, -90, -90, 0]]]]\n")
    with pytest.raises(TableError, match=r"real_pos\[0\]\[0\]\[0\]\[0\]' = 120 is invalid: expected a joint angle"):
        taught_from_table(path, "real_pos")
