"""ur3hanoi.plots.audit and ``check-table --plot``: the picture marks exactly the suspect entries, in red, labelled
with tower/height/pose and the measured error; bad outputs and a missing matplotlib are one-line errors."""

from __future__ import annotations

import re
import sys
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.recorded_tables import recorded_q, table_doc, typo, write_table
from ur3hanoi.audit import audit_table
from ur3hanoi.cli import main
from ur3hanoi.labfile import read_recorded_table
from ur3hanoi.plots.audit import SUSPECT_COLOUR, fitted_reference, write_audit_plot
from ur3hanoi.station import load_station

TYPO_SLOT = (1, 2, 0)  # tower 2 height 3 on


@cache
def _q(with_typo: bool) -> np.ndarray:
    q = recorded_q(load_station("lab_real"), np.random.default_rng(3))
    return typo(q, TYPO_SLOT, 1, -10.0) if with_typo else q


def _table(tmp_path: Path, with_typo: bool) -> Path:
    return write_table(tmp_path / "hand.yaml", "real_pos", table_doc(_q(with_typo), alias_shared=False))


def _red_pixels(png: Path) -> int:
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    ref = np.array([int(SUSPECT_COLOUR[i:i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(img - ref).max(axis=-1) <= 12).sum())


def test_suspects_are_marked_in_red_and_only_them(tmp_path: Path) -> None:
    base = load_station("lab_real")
    red = {}
    for with_typo in (False, True):
        path = _table(tmp_path, with_typo)
        table = read_recorded_table(path, "real_pos")
        report = audit_table(table, base)
        assert len(report.suspects) == (1 if with_typo else 0)
        out = write_audit_plot(tmp_path / f"audit{with_typo}.png", report, table, fitted_reference(table, base))
        red[with_typo] = _red_pixels(out)
    assert red[False] < 120  # the legend's marker only
    assert red[True] - red[False] > 300  # two X markers, two error lines, two labels


def test_svg_labels_the_suspect_with_its_slot_and_error(tmp_path: Path) -> None:
    path = _table(tmp_path, True)
    table = read_recorded_table(path, "real_pos")
    base = load_station("lab_real")
    report = audit_table(table, base)
    write_audit_plot(tmp_path / "audit.svg", report, table, fitted_reference(table, base))
    svg = (tmp_path / "audit.svg").read_text()
    # matplotlib writes text as glyph paths with the string in a comment.
    labels = re.findall(r"<!-- (tower \d height \d (?:on|above)) -->", svg)
    errors = re.findall(r"<!-- ([\d.]+) mm -->", svg)
    assert labels == ["tower 2 height 3 on"] * 2  # top and side view
    assert [float(e) for e in errors] == pytest.approx([report.suspects[0].error_mm] * 2, abs=0.05)


def test_fitted_reference_is_the_audits_grid(tmp_path: Path) -> None:
    table = read_recorded_table(_table(tmp_path, True), "real_pos")
    base = load_station("lab_real")
    grid = fitted_reference(table, base)
    report = audit_table(table, base)
    # The entries the audit calls ok are within its threshold of this grid.
    from ur3hanoi.calibrate.grid_fit import measure
    from ur3hanoi.grid import T_world_tcp

    for e in report.entries:
        if e.status == "ok":
            p = measure(grid, [table.q[e.tower, e.height, e.k]]).p_world[0]
            err = 1e3 * np.linalg.norm(p - T_world_tcp(grid, e.tower, e.height, e.k).translation)
            assert err == pytest.approx(e.error_mm, abs=0.2)


def test_cli_plot_writes_the_picture_and_keeps_the_exit_code(tmp_path: Path) -> None:
    path = _table(tmp_path, True)
    out = tmp_path / "audit.png"
    assert main(["check-table", str(path), "--key", "real_pos", "--fit", "--plot", str(out)]) == 1
    assert _red_pixels(out) > 420


def test_cli_plot_refuses_other_extensions_before_any_work(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _table(tmp_path, True)
    assert main(["check-table", str(path), "--key", "real_pos", "--fit", "--plot", str(tmp_path / "a.jpg")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a.jpg" in err[0] and ".png, .svg, .pdf" in err[0]
    assert not (tmp_path / "a.jpg").exists()


def test_cli_plot_without_matplotlib_names_the_extra(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib -> ImportError
    path = _table(tmp_path, True)
    assert main(["check-table", str(path), "--key", "real_pos", "--fit", "--plot", str(tmp_path / "a.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install 'ur3hanoi[plot]'" in err[0]
