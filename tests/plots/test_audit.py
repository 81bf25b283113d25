"""ur3hanoi.plots.audit and ``check-table --plot``: the picture draws what the audit measured (its points and its
reference, no fit of its own), flagged entries in red labelled with tower/height/pose and the report's error,
warned ones in orange, the rule in the title; bad outputs and a missing matplotlib are one-line errors."""

from __future__ import annotations

import re
import sys
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tests.support.recorded_tables import R_tcp, pose_q, recorded_q, table_doc, typo, write_table
from ur3hanoi.audit import AuditReport, audit_table, check_against
from ur3hanoi.cli import main
from ur3hanoi.plots.audit import (
    OK_COLOUR,
    REFERENCE_GID,
    SUSPECT_COLOUR,
    WARN_COLOUR,
    audit_figure,
    write_audit_plot,
)
from ur3hanoi.station.calibration import load_station
from ur3hanoi.station.grid import ON, T_world_tcp
from ur3hanoi.tables import read_recorded_table
from ur3hanoi.tables.ik_table import generate_table

TYPO_SLOT = (1, 2, 0)  # tower 2 height 3 on: a 10 deg shoulder typo
WARN_SLOT = (1, 1, 0)  # tower 2 height 2 on: re-recorded 6.5 mm off its tower's line


@cache
def _q(kind: str) -> np.ndarray:
    """``clean``/``typo``: noisy hand-recorded-like tables; ``warn``/``exact-typo``: exact ones, one entry edited."""
    st = load_station("lab_real")
    if kind == "warn":
        q = recorded_q(st, None)
        q[WARN_SLOT] = pose_q(st, T_world_tcp(st, *WARN_SLOT).translation + np.array([0.0, 0.0065, 0.0]),
                              R_tcp(st.tool_yaw))
        return q
    if kind == "exact-typo":
        return typo(generate_table(st).q, TYPO_SLOT, 1, -10.0)
    q = recorded_q(st, np.random.default_rng(3))
    return typo(q, TYPO_SLOT, 1, -10.0) if kind == "typo" else q


def _table(tmp_path: Path, kind: str) -> Path:
    return write_table(tmp_path / f"{kind}.yaml", "real_pos", table_doc(_q(kind), alias_shared=False))


def _audit(tmp_path: Path, kind: str, calibration: bool = False) -> AuditReport:
    table = read_recorded_table(_table(tmp_path, kind), "real_pos")
    st = load_station("lab_real")
    return check_against(table, st) if calibration else audit_table(table, st)


def _pixels(png: Path, colour: str) -> int:
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    ref = np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(img - ref).max(axis=-1) <= 12).sum())


def test_red_only_for_a_flagged_entry_and_orange_only_for_a_warning(tmp_path: Path) -> None:
    red, orange = {}, {}
    for kind in ("clean", "typo", "warn"):
        report = _audit(tmp_path, kind)
        assert (len(report.suspects), len(report.warnings)) == {"clean": (0, 0), "typo": (1, 0), "warn": (0, 1)}[kind]
        out = write_audit_plot(tmp_path / f"{kind}.png", report)
        red[kind], orange[kind] = _pixels(out, SUSPECT_COLOUR), _pixels(out, WARN_COLOUR)
    assert red["clean"] == red["warn"] == 0
    assert red["typo"] > 300  # two crosses, two lines to the slot, two labels, the legend's cross
    assert orange["clean"] == orange["typo"] == 0
    assert orange["warn"] > 140  # two dots and two short lines to the slot (~140 px), the legend's dot (~70 px)


@pytest.mark.parametrize("kind", ["typo", "warn"])
def test_each_entry_is_drawn_at_its_measured_point_in_its_status_colour(kind: str, tmp_path: Path) -> None:
    report = _audit(tmp_path, kind)
    top = audit_figure(report).axes[0]
    drawn: dict[str, list[tuple[float, float]]] = {"ok": [], "warn": [], "suspect": []}
    colour = {OK_COLOUR: "ok", WARN_COLOUR: "warn", SUSPECT_COLOUR: "suspect"}
    for ln in top.lines:
        if ln.get_marker() in ("o", "X") and ln.get_markerfacecolor() in colour:
            drawn[colour[str(ln.get_markerfacecolor())]] += list(zip(ln.get_xdata(), ln.get_ydata(), strict=True))
    for status, points in drawn.items():
        want = sorted((1e3 * e.point_m[0], 1e3 * e.point_m[1]) for e in report.entries if e.status == status)
        assert len(want) == {"ok": 17, "warn": int(kind == "warn"), "suspect": int(kind == "typo")}[status]
        np.testing.assert_allclose(np.array(sorted(points)).reshape(-1, 2), np.array(want).reshape(-1, 2),
                                   atol=1e-9)


def test_svg_labels_the_flagged_entry_with_its_slot_and_the_reports_error(tmp_path: Path) -> None:
    report = _audit(tmp_path, "typo")
    write_audit_plot(tmp_path / "audit.svg", report)
    svg = (tmp_path / "audit.svg").read_text()
    # matplotlib writes text as glyph paths with the string in a comment.
    labels = re.findall(r"<!-- (tower \d height \d (?:on|above)) -->", svg)
    errors = re.findall(r"<!-- ([\d.]+) mm, ([\d.]+) deg -->", svg)  # the shoulder typo tilts it too
    entry = next(e for e in report.entries if e.status == "suspect")
    assert labels == ["tower 2 height 3 on"] * 2  # top and side view
    np.testing.assert_allclose(np.array(errors, dtype=float), [[report.suspects[0].error_mm, entry.tilt_deg]] * 2,
                               atol=0.05)
    assert entry.tilt_deg > report.thresholds.deg


def _drawn_towers(report: AuditReport) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Per tower (from 1): the reference line's points as drawn, top view (x, y) and side view (z) [mm]."""
    fig = audit_figure(report)
    top, side = fig.axes[:2]
    out = {}
    for t in range(1, 4):
        (a,) = [ln for ln in top.lines if ln.get_gid() == REFERENCE_GID.format(t)]
        (b,) = [ln for ln in side.lines if ln.get_gid() == REFERENCE_GID.format(t)]
        out[t] = (np.column_stack([a.get_xdata(), a.get_ydata()]), np.asarray(b.get_ydata(), dtype=float))
    return out


@pytest.mark.parametrize("calibration", [False, True], ids=["fit", "calibration"])
def test_the_reference_drawn_is_the_audits(calibration: bool, tmp_path: Path) -> None:
    report = _audit(tmp_path, "exact-typo" if calibration else "typo", calibration)
    assert [(s.tower, s.height, s.k) for s in report.suspects] == [TYPO_SLOT]
    drawn = _drawn_towers(report)
    st = load_station("lab_real")
    for t in range(3):
        fitted = 1e3 * np.array([e.fitted_m for e in report.entries if e.tower == t and e.k == ON])
        xy, z = drawn[t + 1]
        np.testing.assert_allclose(xy, fitted[:, :2], atol=1e-9)
        np.testing.assert_allclose(z, fitted[:, 2], atol=1e-9)
        if calibration:  # against a calibration the reference is its grid
            grid = 1e3 * np.array([T_world_tcp(st, t, h, ON).translation for h in range(st.n_heights)])
            np.testing.assert_allclose(fitted, grid, atol=1e-9)
    # Every contact the fitted audit calls ok is within its rule of the reference drawn.
    for e in report.entries:
        if e.status == "ok" and e.k == ON and report.rule is not None:
            assert 1e3 * np.linalg.norm(np.subtract(e.point_m, e.fitted_m)) <= report.rule.flag_mm


@pytest.mark.parametrize("calibration", [False, True], ids=["fit", "calibration"])
def test_the_title_states_the_rule(calibration: bool, tmp_path: Path) -> None:
    report = _audit(tmp_path, "exact-typo" if calibration else "typo", calibration)
    text = audit_figure(report).get_suptitle()
    (mm, deg), = re.findall(r"flagged over ([\d.]+) mm / ([\d.]+) deg", text)
    want = ((report.rule.flag_mm, report.rule.flag_deg) if report.rule is not None else
            (report.thresholds.mm, report.thresholds.deg))
    assert (float(mm), float(deg)) == pytest.approx(want, abs=1e-9)
    assert (float(mm), float(deg)) == pytest.approx((1.0, 0.5) if calibration else (8.0, 5.0), abs=1e-9)


@pytest.mark.parametrize("reference", [["--fit"], ["--calibration", "lab_real"]], ids=["fit", "calibration"])
def test_cli_plot_writes_the_picture_and_keeps_the_exit_code(reference: list[str], tmp_path: Path) -> None:
    path = _table(tmp_path, "typo" if reference == ["--fit"] else "exact-typo")
    out = tmp_path / "audit.png"
    assert main(["check-table", str(path), "--key", "real_pos", *reference, "--plot", str(out)]) == 1
    assert _pixels(out, SUSPECT_COLOUR) > 300 and _pixels(out, WARN_COLOUR) == 0


def test_cli_plot_refuses_other_extensions_before_any_work(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = _table(tmp_path, "typo")
    assert main(["check-table", str(path), "--key", "real_pos", "--fit", "--plot", str(tmp_path / "a.jpg")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a.jpg" in err[0] and ".png, .svg, .pdf" in err[0]
    assert not (tmp_path / "a.jpg").exists()


def test_cli_plot_without_matplotlib_names_the_extra(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib -> ImportError
    path = _table(tmp_path, "typo")
    assert main(["check-table", str(path), "--key", "real_pos", "--fit", "--plot", str(tmp_path / "a.png")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install 'ur3hanoi[plot]'" in err[0]
