"""The teach session's file: every record written at once in the taught-points format (degrees, one point a line),
continued when it exists, refused (and left as it was) when it is another station's or in radians."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import LAB_REAL
from ur3hanoi.calibrate.taught import DEG_DECIMALS, load_taught
from ur3hanoi.cli import main
from ur3hanoi.errors import TaughtPointsError
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.tables.ik_table import generate_table
from ur3hanoi.teach.taught_file import open_taught


@pytest.fixture(scope="module")
def base() -> Station:
    return load_station(LAB_REAL)


@pytest.fixture(scope="module")
def contacts(base: Station) -> np.ndarray:
    """The base's own contact poses [rad], Q[t][h]."""
    return generate_table(base).q[:, :, 0]


def test_records_are_written_at_once_and_read_back_exactly(tmp_path: Path, base: Station, contacts: np.ndarray
                                                           ) -> None:
    path = tmp_path / "taught.yaml"
    f = open_taught(path, base, "lab_real")
    assert f.points == () and not path.exists()
    for t, h in ((0, 2), (1, 0), (2, 0)):
        f, said = f.with_point(t, h, tuple(contacts[t, h]))
        f.save()
        assert said.startswith(f"recorded tower {t + 1} height {h + 1}: point ")
        back = load_taught(path)
        assert [p.q for p in back.points] == [p.q for p in f.points]  # what the session fits is what the file holds
    text = path.read_text()
    assert "units: deg" in text and 'station: "lab_real_example"' in text
    assert len([line for line in text.splitlines() if line.startswith("  - {tower:")]) == 3
    for p in back.points:
        for v, exact in zip(p.q, contacts[p.tower, p.height], strict=True):
            assert abs(math.degrees(v) - math.degrees(exact)) <= 0.5 * 10**-DEG_DECIMALS + 1e-12


def test_calibrate_reads_the_file_unchanged(tmp_path: Path, base: Station, contacts: np.ndarray,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    f = open_taught(tmp_path / "taught.yaml", base, "lab_real")
    for t, h in ((0, 2), (1, 0), (2, 0)):
        f = f.with_point(t, h, tuple(contacts[t, h]))[0]
    f.save()
    out = tmp_path / "station.yaml"
    assert main(["calibrate", "--taught", str(f.path), "--base", "lab_real", "-o", str(out)]) == 0
    fitted = load_station(out)
    assert np.allclose(fitted.tower_origins, base.tower_origins, atol=5e-6)  # 0.0001 deg of rounding: um
    capsys.readouterr()


def test_recording_a_slot_again_replaces_it_and_undo_removes_the_last(tmp_path: Path, base: Station,
                                                                     contacts: np.ndarray) -> None:
    f = open_taught(tmp_path / "t.yaml", base, "lab_real")
    f = f.with_point(0, 2, tuple(contacts[0, 2]))[0]
    f = f.with_point(1, 0, tuple(contacts[1, 0]))[0]
    f, said = f.with_point(0, 2, tuple(contacts[0, 2] + 0.01))
    assert "again (the earlier pose is replaced)" in said
    assert f.slots == ((1, 0, 0), (0, 2, 0)) and [p.index for p in f.points] == [0, 1]
    f.save()
    f, said = f.without_last()
    f.save()
    assert said == "undone: points[1] (tower 1 height 3 on) removed"
    assert [(p.tower, p.height) for p in load_taught(f.path).points] == [(1, 0)]
    f = f.without_last()[0]
    f.save()
    assert not f.path.exists()  # a taught-points file holds at least one point
    assert f.without_last()[1] == "nothing to undo: no point recorded yet"


def test_a_second_session_continues_the_file(tmp_path: Path, base: Station, contacts: np.ndarray) -> None:
    f = open_taught(tmp_path / "t.yaml", base, "lab_real")
    f = f.with_point(0, 2, tuple(contacts[0, 2]))[0].with_point(1, 0, tuple(contacts[1, 0]))[0]
    f.save()
    again = open_taught(f.path, base, "lab_real")
    assert again.points == f.points


def test_a_hand_typed_file_without_a_station_is_continued(tmp_path: Path, base: Station) -> None:
    path = tmp_path / "hand.yaml"
    path.write_text("units: deg\npoints:\n  - {tower: 1, height: 1, q: [110.87, -64.65, 136.28, -161.63, -90, 20]}\n")
    assert len(open_taught(path, base, "lab_real").points) == 1


@pytest.mark.parametrize(("text", "message"), [
    ("units: rad\npoints:\n  - {tower: 1, height: 1, q: [1.9, -1.1, 2.3, -2.8, -1.57, 0.36]}\n",
     "units: rad: teach records degrees"),
    ('units: deg\nstation: "ur3e_sim"\npoints:\n  - {tower: 1, height: 1, q: [110, -64, 136, -161, -90, 20]}\n',
     "taught for station 'ur3e_sim', not for 'lab_real_example' (lab_real)"),
    ("units: deg\npoints:\n  - {tower: 4, height: 1, q: [110, -64, 136, -161, -90, 20]}\n",
     "(tower 4 height 1 on) is outside the grid of lab_real (towers 1..3, heights 1..3)"),
    ("units: deg\npoints: [\n", "t.yaml"),
])
def test_another_stations_or_units_file_is_refused_and_left_as_it_was(tmp_path: Path, base: Station, text: str,
                                                                      message: str) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(text)
    with pytest.raises(TaughtPointsError, match=r"t\.yaml") as err:
        open_taught(path, base, "lab_real")
    assert message in str(err.value) and "\n" not in str(err.value)
    assert path.read_text() == text
