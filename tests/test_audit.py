"""Auditing tables: synthetic hand-recorded tables (1-3 mm noise) with one injected gross error each; the audit must
rank the injected entry first and fit the rest within the noise. Also the strict check against a calibration, the
report's JSON and text, and the `check-table` command."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml

from ur3hanoi.audit import AuditReport, audit_table, check_against, default_base
from ur3hanoi.cli import main
from ur3hanoi.errors import TaughtPointsError
from ur3hanoi.grid import ABOVE, ON
from ur3hanoi.labfile import read_recorded_table
from ur3hanoi.station import Station, load_station
from ur3hanoi.waypoints import generate_table

from . import recorded_tables as rt

Slot = tuple[int, int, int]
NOISE_MAX_MM = rt.NOISE_MM[1]
Inject = Callable[[Station, np.ndarray, np.random.Generator], tuple[np.ndarray, list[Slot], str]]


def _slot(rng: np.random.Generator, st: Station) -> Slot:
    return (int(rng.integers(st.n_towers)), int(rng.integers(st.n_heights)), ON)


def typo10(st: Station, q: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    slot, joint = _slot(rng, st), int(rng.integers(6))
    return rt.typo(q, slot, joint, 10.0), [slot], f"typo in joint {joint + 1}"


def typo3(st: Station, q: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    slot, joint = _slot(rng, st), int(rng.integers(6))
    return rt.typo(q, slot, joint, -3.0), [slot], ""


def duplicated(st: Station, q: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    src = _slot(rng, st)
    dst = (src[0], (src[1] + 1) % st.n_heights, ON)
    return rt.duplicate(q, src, dst), [dst], "a copied entry"


def swapped_heights(st: Station, q: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    a = _slot(rng, st)
    b = (a[0], (a[1] + 1 + int(rng.integers(st.n_heights - 1))) % st.n_heights, ON)
    return rt.swap(q, a, b), [a, b], "swapped heights"


def swapped_towers(st: Station, q: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    a = _slot(rng, st)
    b = ((a[0] + 1 + int(rng.integers(st.n_towers - 1))) % st.n_towers, a[1], ON)
    return rt.swap(q, a, b), [a, b], "swapped towers"


ERRORS: dict[str, Inject] = {"typo10": typo10, "typo3": typo3, "duplicated": duplicated,
                             "swapped-heights": swapped_heights, "swapped-towers": swapped_towers}


def _audit(tmp_path: Path, station: str, variant: str, q: np.ndarray, key: str = "real_pos") -> AuditReport:
    st = load_station(station)
    if variant == "shared-above":
        q = rt.shared_above(st, q)
    path = rt.write_table(tmp_path / "hand.yaml", key, rt.table_doc(q, contact_only=variant == "contact-only"))
    return audit_table(read_recorded_table(path, key), st)


# ------------------------------------------------------------------------------------------------ the matrix


# One above pose per tower cannot serve the flat layout's rows: that case is flagged (see further down).
MATRIX = [(station, error, variant) for station in ("lab_real", "lab_sim") for error in sorted(ERRORS)
          for variant in ("full", "contact-only", "shared-above") if (station, variant) != ("lab_sim", "shared-above")]


@pytest.mark.parametrize(("station", "error", "variant"), MATRIX, ids=["-".join(m) for m in MATRIX])
def test_audit_ranks_the_injected_error_first(station: str, error: str, variant: str, tmp_path: Path) -> None:
    st = load_station(station)
    rng = np.random.default_rng(sorted(ERRORS).index(error) * 10 + len(variant))
    q, injected, said = ERRORS[error](st, rt.recorded_q(st, rng), rng)
    report = _audit(tmp_path, station, variant, q)
    got = [(s.tower, s.height, s.k) for s in report.suspects]
    assert sorted(got[:len(injected)]) == sorted(injected), report.text()
    assert got[len(injected):] == [], report.text()
    assert said in report.suspects[0].reason
    # The rest is fitted within the noise; the injected entries are far off it.
    assert report.rms_mm < NOISE_MAX_MM
    n_fitted = 9 if variant != "full" else 18
    assert report.points_used == n_fitted - len(injected)
    by_slot = {(e.tower, e.height, e.k): e for e in report.entries}
    th = report.thresholds
    assert all(by_slot[s].error_mm > th.mm or by_slot[s].rot_deg > th.deg for s in injected)


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("variant", ["full", "contact-only", "shared-above"])
def test_clean_hand_recorded_tables_have_no_suspect(variant: str, seed: int, tmp_path: Path) -> None:
    st = load_station("lab_real")
    report = _audit(tmp_path, "lab_real", variant, rt.recorded_q(st, np.random.default_rng(seed)))
    assert report.suspects == () and not report.failed, report.text()
    assert report.rms_mm < NOISE_MAX_MM
    # Derived from the data: above the 3 mm floor, below what a gross error is.
    assert 3.0 <= report.thresholds.mm < 15.0 and report.thresholds.derived


def test_shared_above_over_a_flat_layout_is_flagged(tmp_path: Path) -> None:
    # On the flat simulator layout "heights" are rows 0.10 m apart: one above pose per tower is over one row only.
    st = load_station("lab_sim")
    report = _audit(tmp_path, "lab_sim", "shared-above", rt.recorded_q(st, np.random.default_rng(4)), "sim_pos")
    flagged = {(s.tower, s.height, s.k) for s in report.suspects}
    assert flagged == {(t, h, ABOVE) for t in range(3) for h in range(2)}
    assert all("the above pose shared by heights 1, 2, 3 of tower" in s.reason for s in report.suspects)
    assert report.shared_above == ((0, (0, 1, 2)), (1, (0, 1, 2)), (2, (0, 1, 2)))


def test_a_typo_names_the_joint_with_degrees_and_radians(tmp_path: Path) -> None:
    st = load_station("lab_real")
    q = rt.recorded_q(st, np.random.default_rng(11))
    recorded = q[1, 2, ON, 1] - math.radians(10.0)
    report = _audit(tmp_path, "lab_real", "full", rt.typo(q, (1, 2, ON), 1, -10.0))
    (suspect,) = report.suspects
    assert suspect.reason.startswith(f"{suspect.error_mm:.1f} mm from the grid fitted to the other 8 contacts and 9 "
                                     "above poses; likely a typo in joint 2 (shoulder): recorded "
                                     f"{math.degrees(recorded):.1f} deg ({recorded:.3f} rad), the grid predicts ")
    predicted = float(suspect.reason.split("the grid predicts ")[1].split(" deg")[0])
    assert predicted == pytest.approx(math.degrees(q[1, 2, ON, 1]), abs=0.5)


def test_missing_entries_are_listed_and_the_rest_used(tmp_path: Path) -> None:
    st = load_station("lab_real")
    q = rt.recorded_q(st, np.random.default_rng(5))
    missing = [(0, 2, ON), (1, 0, ABOVE), (2, 1, ABOVE)]
    path = rt.write_table(tmp_path / "t.yaml", "real_pos", rt.table_doc(q, missing=missing))
    report = audit_table(read_recorded_table(path, "real_pos"), st)
    assert [(e.tower, e.height, e.k) for e in report.missing] == missing
    assert report.points_used == 15 and report.suspects == ()
    assert "missing (3 of 18, not used): tower 1 height 3 on, tower 2 height 1 above, tower 3 height 2 above" in \
        report.text()


def test_too_little_left_to_fit_says_what_is_needed(tmp_path: Path) -> None:
    st = load_station("lab_real")
    q = rt.recorded_q(st, None)
    path = rt.write_table(tmp_path / "t.yaml", "real_pos",
                          rt.table_doc(q, missing=[(2, h, k) for h in range(3) for k in (ON, ABOVE)]))
    with pytest.raises(TaughtPointsError, match=r"too little left to fit the grid: it needs a usable contact \('on'\) "
                                                r"pose on every tower \(3 towers\).*tower\(s\) 3 have none"):
        audit_table(read_recorded_table(path, "real_pos"), st)


# ---------------------------------------------------------------------------------------- strict check, JSON


def test_check_against_a_calibration_is_strict_and_explains(lab_real: Station, tmp_path: Path) -> None:
    q = generate_table(lab_real).q
    path = rt.write_table(tmp_path / "t.yaml", "real_pos", rt.table_doc(rt.typo(q, (2, 0, ABOVE), 3, 2.0),
                                                                        missing=[(0, 0, ABOVE)]))
    report = check_against(read_recorded_table(path, "real_pos"), lab_real)
    assert [(s.tower, s.height, s.k) for s in report.suspects] == [(2, 0, ABOVE)]
    assert "(tolerance 1 mm / 0.5 deg); likely a typo in joint 4 (wrist 1)" in report.suspects[0].reason
    assert [e.status for e in report.entries].count("missing") == 1 and report.points_used == 17
    assert report.text().splitlines()[-1].startswith("16/17 entries within 1.0 mm / 0.5 deg (worst ")


def test_json_has_the_documented_shape(tmp_path: Path) -> None:
    st = load_station("lab_real")
    q, _, _ = swapped_towers(st, rt.recorded_q(st, np.random.default_rng(8)), np.random.default_rng(8))
    path = rt.write_table(tmp_path / "t.yaml", "real_pos", rt.table_doc(q, missing=[(0, 0, ABOVE)]))
    doc = json.loads(json.dumps(audit_table(read_recorded_table(path, "real_pos"), st).to_json()))
    assert set(doc) == {"entries", "suspects", "fit"}
    assert len(doc["entries"]) == 18
    for e in doc["entries"]:
        assert {"tower", "height", "pose", "error_mm", "tilt_deg", "status"} <= set(e)
        assert 1 <= e["tower"] <= 3 and 1 <= e["height"] <= 3 and e["pose"] in ("on", "above")
        assert e["status"] in ("ok", "suspect", "missing")
        assert (e["error_mm"] is None) == (e["status"] == "missing")
    assert [(e["tower"], e["height"], e["pose"]) for e in doc["entries"][:3]] == [(1, 1, "on"), (1, 1, "above"),
                                                                                  (1, 2, "on")]
    assert doc["entries"][1]["status"] == "missing" and doc["entries"][1]["tilt_deg"] is None
    assert len(doc["suspects"]) == 2
    for s in doc["suspects"]:
        assert {"tower", "height", "pose", "error_mm", "reason"} <= set(s) and "swapped towers" in s["reason"]
    errors = [s["error_mm"] for s in doc["suspects"]]
    assert errors == sorted(errors, reverse=True)  # worst first
    suspect_slots = {(s["tower"], s["height"], s["pose"]) for s in doc["suspects"]}
    assert suspect_slots == {(e["tower"], e["height"], e["pose"]) for e in doc["entries"] if e["status"] == "suspect"}
    assert doc["fit"]["points_used"] == 15 and 0 < doc["fit"]["rms_mm"] < NOISE_MAX_MM


# ------------------------------------------------------------------------------------------------------- CLI


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    rc = main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


def test_cli_fit_exit_codes_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    st = load_station("lab_real")
    q = rt.recorded_q(st, np.random.default_rng(9))
    clean = rt.write_table(tmp_path / "clean.yaml", "real_pos", rt.table_doc(q, contact_only=True))
    rc, out, err = _run(["check-table", str(clean), "--key", "real_pos", "--fit"], capsys)
    assert rc == 0 and err == ""
    assert "missing (9 of 18, not used)" in out and "suspect over " in out and "= max(3 mm, 5 sigma)" in out
    bad = rt.write_table(tmp_path / "bad.yaml", "real_pos", rt.table_doc(rt.typo(q, (0, 1, ON), 0, 10.0)))
    rc, out, err = _run(["check-table", str(bad), "--key", "real_pos", "--fit", "--json"], capsys)
    assert rc == 1 and err == ""
    doc = json.loads(out)
    assert out.count("\n") == 1
    assert (doc["suspects"][0]["tower"], doc["suspects"][0]["height"], doc["suspects"][0]["pose"]) == (1, 2, "on")
    assert "likely a typo in joint 1 (base)" in doc["suspects"][0]["reason"]


def test_cli_fit_uses_the_key_s_default_base_or_the_given_one(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    assert default_base("sim_pos") == "lab_sim" and default_base("real_pos") == "lab_real"
    sim = load_station("lab_sim")
    path = rt.write_table(tmp_path / "t.yaml", "sim_pos", rt.table_doc(generate_table(sim).q))
    rc, out, _ = _run(["check-table", str(path), "--key", "sim_pos", "--fit"], capsys)
    assert rc == 0 and "robot base, tool and home of lab_sim" in out
    # With lab_real's robot base (at the world origin) the entries still fit a grid (a base translation only moves
    # the tower origins), but lab_real's layout is stacked and the fitted step is horizontal: not a sound station.
    rc, out, _ = _run(["check-table", str(path), "--key", "sim_pos", "--fit", "--base", "lab_real"], capsys)
    assert rc == 1 and "robot base, tool and home of lab_real" in out
    assert "suspects" not in out and "the fit is not sound: the fitted grid is invalid (a vertical vector" in out


@pytest.mark.parametrize(
    ("extra", "fragment"),
    [(["--base", "lab_real", "--calibration", "lab_real"], "--base is only used with --fit"),
     (["--fit", "--calibration", "lab_real"], "argument --calibration: not allowed with argument --fit"),
     ([], "one of the arguments --calibration --fit is required")],
    ids=["base-without-fit", "both", "neither"],
)
def test_cli_reference_options(extra: list[str], fragment: str, capsys: pytest.CaptureFixture[str],
                               repo: Path) -> None:
    rc, _, err = _run(["check-table", str(repo / "tables/lab2_data.yaml"), "--key", "real_pos", *extra], capsys)
    assert rc == 2 and fragment in err and err.count("\n") == 1


def test_cli_partial_table_against_a_calibration(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                 lab_real: Station) -> None:
    doc = rt.table_doc(generate_table(lab_real).q, contact_only=True)
    path = rt.write_table(tmp_path / "t.yaml", "real_pos", doc)
    rc, out, _ = _run(["check-table", str(path), "--key", "real_pos", "--calibration", "lab_real"], capsys)
    assert rc == 0
    assert out.splitlines()[-1].startswith("9/9 entries within 1.0 mm / 0.5 deg")
    assert out.count(" missing\n") == 9
    # Before: "got None". A table file with nulls is still valid YAML for the lab's own loader.
    assert yaml.safe_load(path.read_text())["real_pos"][0][0] == doc[0][0]
