"""Auditing tables. `check-table --fit` on recorded-like tables (1-2 mm jitter, a heading per tower, wrist 3 turned
per entry, a small table-wide tilt, above poses 15-60 mm over the stacks; stacked stations with towers 5-15 cm apart
and the flat Gazebo layout): nothing flagged on clean tables over many seeds, one injected gross error named first,
the rule in mm and deg entry by entry, the words, the flat layout with the default base, the conditioning notes.
Also the strict check against a calibration, the JSON and text reports, and the `check-table` command."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.support import recorded_tables as rt
from ur3hanoi.audit import AuditReport, audit_table, check_against, default_base, rule
from ur3hanoi.cli import main
from ur3hanoi.errors import TaughtPointsError
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.station.grid import ABOVE, ON, T_world_tcp
from ur3hanoi.tables import read_recorded_table
from ur3hanoi.tables.ik_table import generate_table

Slot = tuple[int, int, int]
Inject = Callable[[Station, np.random.Generator], tuple[np.ndarray, list[Slot], str]]


def _station(layout: str, rng: np.random.Generator) -> Station:
    return rt.flat_station() if layout == "flat" else rt.stacked_station(rng)


def _key(layout: str) -> str:
    return "sim_pos" if layout == "flat" else "real_pos"


def _audit(tmp_path: Path, q: np.ndarray, key: str = "real_pos", base: str | None = None, contact_only: bool = False,
           missing: list[Slot] | None = None) -> AuditReport:
    path = rt.write_table(tmp_path / "hand.yaml", key, rt.table_doc(q, contact_only=contact_only,
                                                                    missing=missing or []))
    return audit_table(read_recorded_table(path, key), load_station(base or default_base(key)))


def _slot(rng: np.random.Generator, st: Station) -> Slot:
    return (int(rng.integers(st.n_towers)), int(rng.integers(st.n_heights)), ON)


def _other_height(rng: np.random.Generator, st: Station, s: Slot) -> Slot:
    return (s[0], (s[1] + 1 + int(rng.integers(st.n_heights - 1))) % st.n_heights, ON)


def _sign(rng: np.random.Generator) -> float:
    return 1.0 if rng.random() < 0.5 else -1.0


def typo_j1(st: Station, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    s = _slot(rng, st)
    return rt.typo(rt.recorded_like(st, rng).q, s, 0, _sign(rng) * 10.0), [s], "likely a typo in joint 1 (base)"


def typo_j2(st: Station, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    s = _slot(rng, st)
    return rt.typo(rt.recorded_like(st, rng).q, s, 1, _sign(rng) * 3.0), [s], "likely a typo in joint 2 (shoulder)"


def swapped_heights(st: Station, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    a = _slot(rng, st)
    b = _other_height(rng, st, a)
    return rt.swap(rt.recorded_like(st, rng).q, a, b), [a, b], "swapped heights"


def swapped_towers(st: Station, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    a = _slot(rng, st)
    b = ((a[0] + 1 + int(rng.integers(st.n_towers - 1))) % st.n_towers, a[1], ON)
    return rt.swap(rt.recorded_like(st, rng).q, a, b), [a, b], "swapped towers"


def duplicated(st: Station, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    src = _slot(rng, st)
    dst = _other_height(rng, st, src)
    return rt.duplicate(rt.recorded_like(st, rng).q, src, dst), [dst], "a copied entry"


def tilted(st: Station, rng: np.random.Generator) -> tuple[np.ndarray, list[Slot], str]:
    s = _slot(rng, st)
    return rt.recorded_like(st, rng, tilted=s).q, [s], "its suction axis is"


ERRORS: dict[str, Inject] = {"typo-j1-10deg": typo_j1, "typo-j2-3deg": typo_j2, "swapped-heights": swapped_heights,
                             "swapped-towers": swapped_towers, "duplicated": duplicated, "tilt-5-6deg": tilted}
CLEAN_SEEDS = 30
ERROR_SEEDS = 6


# ------------------------------------------------------------------------------- clean tables, gross errors


@pytest.mark.parametrize("layout", ["stacked", "flat"])
def test_clean_recorded_like_tables_are_never_flagged(layout: str, tmp_path: Path) -> None:
    for seed in range(CLEAN_SEEDS):
        rng = np.random.default_rng(100 + seed)
        report = _audit(tmp_path, rt.recorded_like(_station(layout, rng), rng).q, _key(layout))
        assert report.suspects == () and not report.failed, report.text()
        assert report.layout == layout and report.points_used == 9
        for e in report.entries:  # the rule, entry by entry: what passes is within it
            if e.k == ON:
                assert math.hypot(e.off_line_mm, e.off_level_mm) <= rule.CONTACT_FLAG_MM
                assert e.tilt_deg <= rule.TILT_FLAG_DEG
            else:
                assert e.over_top_mm >= rule.ABOVE_MIN_MM and e.off_line_mm <= rule.ABOVE_FLAG_LINE_MM


@pytest.mark.parametrize(("layout", "error"), [(lay, err) for lay in ("stacked", "flat") for err in ERRORS])
def test_one_gross_error_is_named_first(layout: str, error: str, tmp_path: Path) -> None:
    for seed in range(ERROR_SEEDS):
        rng = np.random.default_rng(1000 * sorted(ERRORS).index(error) + seed)
        q, injected, said = ERRORS[error](_station(layout, rng), rng)
        report = _audit(tmp_path, q, _key(layout))
        named = [(s.tower, s.height, s.k) for s in report.suspects + report.warnings]
        by_slot = {(e.tower, e.height, e.k): e for e in report.entries}
        if error == "tilt-5-6deg":  # flagged over 5 deg as measured from the table's axis, else warned
            assert named[:1] == injected, report.text()
            assert (report.suspects != ()) == (by_slot[injected[0]].tilt_deg > rule.TILT_FLAG_DEG)
        else:
            assert sorted(named[:len(injected)]) == sorted(injected), report.text()
            assert all(by_slot[s].status == "suspect" for s in injected)
        assert said in report.suspects[0].reason if report.suspects else said in report.warnings[0].reason
        assert [s for s in named if s not in injected] == [], report.text()
        assert not report.problem


@pytest.mark.parametrize("error", ["typo-j1-10deg", "swapped-heights", "duplicated"])
@pytest.mark.parametrize("variant", ["contact-only", "shared-above"])
def test_partial_tables_still_name_the_error(error: str, variant: str, tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    st = rt.stacked_station(rng)
    q, injected, said = ERRORS[error](st, rng)
    if variant == "shared-above":
        q = rt.shared_above(st, q)
    report = _audit(tmp_path, q, contact_only=variant == "contact-only")
    assert sorted((s.tower, s.height, s.k) for s in report.suspects) == sorted(injected), report.text()
    assert said in report.suspects[0].reason


# --------------------------------------------------------------------------------------------- the rule


def _exact(st: Station) -> np.ndarray:
    """The grid's poses, exactly, with above poses 30 mm over the top level (the rule's distances are then the
    edits alone)."""
    q = rt.recorded_q(st, None)
    top = max(T_world_tcp(st, t, st.n_heights - 1, ON).translation[2] for t in range(st.n_towers))
    for t in range(st.n_towers):
        for h in range(st.n_heights):
            p = T_world_tcp(st, t, h, ON).translation.copy()
            p[2] = top + 0.030
            q[t, h, ABOVE] = rt.pose_q(st, p, rt.R_tcp(st.tool_yaw))
    return q


def _moved(st: Station, q: np.ndarray, slot: Slot, d_mm: tuple[float, float, float], heading_deg: float = 0.0,
           tilt_deg: float = 0.0, above_mm: float | None = None) -> np.ndarray:
    """``q`` with ``slot`` re-recorded at its grid point (an above pose: ``above_mm`` over the top level) moved by
    ``d_mm``, turned by ``heading_deg`` about the suction axis and tilted by ``tilt_deg``."""
    top = max(T_world_tcp(st, t, st.n_heights - 1, ON).translation[2] for t in range(st.n_towers))
    p = T_world_tcp(st, slot[0], slot[1], ON).translation.copy()
    if above_mm is not None:
        p[2] = top + above_mm * 1e-3
    out = q.copy()
    out[slot] = rt.pose_q(st, p + np.array(d_mm) * 1e-3,
                          rt.R_tcp(st.tool_yaw + math.radians(heading_deg), tilt_deg, tilt_about=0.7))
    return out


@pytest.mark.parametrize(
    ("slot", "edit", "status"),
    [((1, 1, ON), {"d_mm": (4.5, 0.0, 0.0)}, "ok"),            # within 5 mm of its line: never flagged
     ((1, 1, ON), {"d_mm": (0.0, 0.0, -4.5)}, "ok"),           # ... and of its level
     ((1, 1, ON), {"d_mm": (0.0, 6.5, 0.0)}, "warn"),          # 5-8 mm: a warning at most, the table passes
     ((1, 1, ON), {"d_mm": (0.0, 0.0, 9.0)}, "suspect"),       # more than 8 mm off its level: always flagged
     ((1, 1, ON), {"d_mm": (6.0, 6.0, 0.0)}, "suspect"),       # 8.5 mm off its line
     ((1, 1, ON), {"d_mm": (5.8, 0.0, -5.8)}, "suspect"),      # 8.2 mm from where the grid puts it
     ((1, 1, ON), {"d_mm": (0, 0, 0), "heading_deg": 120.0}, "ok"),  # heading is never an error
     ((1, 1, ON), {"d_mm": (0, 0, 0), "tilt_deg": 3.8}, "ok"),       # within 4 deg of the table's axis
     ((1, 1, ON), {"d_mm": (0, 0, 0), "tilt_deg": 4.6}, "warn"),
     ((1, 1, ON), {"d_mm": (0, 0, 0), "tilt_deg": 5.5}, "suspect"),  # more than 5 deg: always flagged
     ((2, 0, ABOVE), {"d_mm": (0, 7.5, 0), "above_mm": 10.5}, "ok"),  # 10 mm over the top, within 8 mm: accepted
     ((2, 0, ABOVE), {"d_mm": (0, 0, 0), "above_mm": 7.0}, "warn"),
     ((2, 0, ABOVE), {"d_mm": (0, 0, 0), "above_mm": 4.0}, "suspect"),      # under 5 mm over the top level
     ((2, 0, ABOVE), {"d_mm": (9.0, 0, 0), "above_mm": 30.0}, "warn"),
     ((2, 0, ABOVE), {"d_mm": (10.5, 0, 0), "above_mm": 30.0}, "suspect"),  # more than 10 mm off the line
     ((2, 0, ABOVE), {"d_mm": (0, 0, 0), "above_mm": 30.0, "tilt_deg": 12.0, "heading_deg": -90.0}, "ok")],
    ids=["line-4.5", "level-4.5", "line-6.5", "level-9", "line-8.5", "off-8.2", "heading-120", "tilt-3.8", "tilt-4.6",
         "tilt-5.5", "above-10.5-line-7.5", "above-7", "above-4", "above-line-9", "above-line-10.5",
         "above-tilt-12"],
)
@pytest.mark.parametrize("layout", ["stacked", "flat"])
def test_the_rule_in_mm_and_deg(layout: str, slot: Slot, edit: dict[str, object], status: str,
                                tmp_path: Path) -> None:
    st = rt.flat_station() if layout == "flat" else load_station("lab_real")
    if layout == "flat" and slot[2] == ABOVE:
        slot = (1, 2, ABOVE)  # (tower 3 height 1 is at the edge of the UR3's reach on the flat layout)
    report = _audit(tmp_path, _moved(st, _exact(st), slot, **edit), _key(layout))  # type: ignore[arg-type]
    by_slot = {(e.tower, e.height, e.k): e for e in report.entries}
    assert by_slot[slot].status == status, report.text()
    assert all(e.status == "ok" for s, e in by_slot.items() if s != slot), report.text()
    assert report.failed == (status == "suspect")
    if slot[2] == ON:
        d = edit["d_mm"]
        assert by_slot[slot].off_line_mm == pytest.approx(math.hypot(d[0], d[1]), abs=0.05)  # type: ignore[index]
        assert by_slot[slot].off_level_mm == pytest.approx(d[2], abs=0.05)  # type: ignore[index]
        assert by_slot[slot].tilt_deg == pytest.approx(edit.get("tilt_deg", 0.0), abs=0.05)
    else:
        assert by_slot[slot].over_top_mm == pytest.approx(edit["above_mm"], abs=0.05)


def test_a_tilted_table_is_judged_by_its_own_axis(tmp_path: Path) -> None:
    # Every entry 3 deg off vertical the same way (a tool mounted a little askew): nothing is off by the rule.
    st = load_station("lab_real")
    q = _exact(st)
    for t in range(3):
        for h in range(3):
            for k in (ON, ABOVE):
                q = _moved(st, q, (t, h, k), (0, 0, 0), tilt_deg=3.0, above_mm=30.0 if k == ABOVE else None)
    report = _audit(tmp_path, q)
    assert report.suspects == report.warnings == () and max(e.tilt_deg for e in report.entries) < 0.01


# ---------------------------------------------------------------------------------------------- the words


def test_a_typo_is_named_with_what_was_measured(tmp_path: Path) -> None:
    rng = np.random.default_rng(11)
    st = rt.stacked_station(rng)
    q = rt.recorded_like(st, rng).q
    recorded = q[1, 2, ON, 1] - math.radians(3.0)
    report = _audit(tmp_path, rt.typo(q, (1, 2, ON), 1, -3.0))
    (suspect,) = report.suspects
    e = next(e for e in report.entries if (e.tower, e.height, e.k) == (1, 2, ON))
    assert suspect.reason.startswith(
        f"suction point {e.error_mm:.1f} mm from where the grid fitted to the other 8 contacts puts it "
        f"({e.off_line_mm:.1f} mm off its tower's line, {abs(e.off_level_mm):.1f} mm ")
    assert "more than 8 mm in all (recording noise is 1-3 mm, " in suspect.reason
    assert (f"likely a typo in joint 2 (shoulder): recorded {math.degrees(recorded):.1f} deg ({recorded:.3f} rad), "
            "the grid predicts ") in suspect.reason
    predicted = float(suspect.reason.split("the grid predicts ")[1].split(" deg")[0])
    assert predicted == pytest.approx(math.degrees(q[1, 2, ON, 1]), abs=0.5)


def test_a_small_deviation_is_not_called_a_typo(tmp_path: Path) -> None:
    # 1.2 deg on the shoulder moves the cup about 7 mm: a warning that says what was measured, no "typo".
    st = load_station("lab_real")
    report = _audit(tmp_path, rt.typo(_exact(st), (0, 1, ON), 1, 1.2))
    assert report.suspects == () and not report.failed
    (warning,) = report.warnings
    assert "typo" not in warning.reason and "within 8 mm in all" in warning.reason
    assert 5.0 < warning.error_mm < 8.0


def test_on_and_above_swapped_are_named(tmp_path: Path) -> None:
    rng = np.random.default_rng(12)
    q = rt.recorded_like(rt.stacked_station(rng), rng).q
    report = _audit(tmp_path, rt.swap(q, (0, 1, ON), (0, 1, ABOVE)))
    assert {(s.tower, s.height, s.k) for s in report.suspects} == {(0, 1, ON), (0, 1, ABOVE)}, report.text()
    assert all("on and above swapped with tower 1 height 2" in s.reason for s in report.suspects)


def test_a_tilt_says_how_far_and_why(tmp_path: Path) -> None:
    st = load_station("lab_real")
    report = _audit(tmp_path, _moved(st, _exact(st), (2, 1, ON), (0, 0, 0), tilt_deg=6.0))
    (suspect,) = report.suspects
    sigma = report.rule.sigma_deg if report.rule else math.nan
    assert sigma == rule.SIGMA_FLOOR_DEG  # the other entries are exact: the scatter is the floor's
    assert suspect.reason == ("its suction axis is 6.0 deg from the table's: more than 5 deg (a suction cup seals "
                              f"within a few degrees, {6.0 / sigma:.0f} sigma of this table's scatter)")


# ---------------------------------------------------------------------------- layout, conditioning, missing


def test_a_flat_table_with_the_stacked_default_base_is_audited_as_flat(tmp_path: Path,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(3)
    q = rt.recorded_like(rt.flat_station(), rng).q
    path = rt.write_table(tmp_path / "t.yaml", "real_pos", rt.table_doc(q))
    rc, out, err = _run(["check-table", str(path), "--key", "real_pos", "--fit"], capsys)
    assert rc == 0 and err == "", out
    assert "a flat layout (the base lab_real is stacked; audited as flat all the same: the course's Gazebo " \
           "tables are flat, `--base lab_sim` gives their world frame)" in out
    assert "0 flagged" in out


def test_a_tower_with_one_contact_is_unchecked_and_says_how_to_check_it(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    q = rt.recorded_like(rt.stacked_station(rng), rng).q
    report = _audit(tmp_path, q, missing=[(2, 1, ON), (2, 2, ON)])
    by_slot = {(e.tower, e.height, e.k): e for e in report.entries}
    assert by_slot[(2, 0, ON)].status == "unchecked" and not report.failed
    assert any("record another height of tower(s) 3 to check them" in n for n in report.notes)


def test_a_table_only_conditioning_stops_says_so(tmp_path: Path) -> None:
    rng = np.random.default_rng(6)
    q = rt.recorded_like(rt.stacked_station(rng), rng).q
    report = _audit(tmp_path, q, missing=[(t, h, ON) for t in range(3) for h in (1, 2)])
    assert report.failed and report.suspects == ()
    assert report.problem.startswith("no contact can be checked against the others") and \
        "record at least two heights on every tower" in report.problem


def test_copied_or_reversed_heights_and_copied_towers_are_a_problem(tmp_path: Path) -> None:
    rng = np.random.default_rng(13)
    q = rt.recorded_like(rt.stacked_station(rng), rng).q
    same = q.copy()
    same[:, :, ON] = q[:, :1, ON]  # every height holds the bottom contact: the grid fits them exactly
    report = _audit(tmp_path, same)
    assert report.failed and report.problem.startswith("the table's levels are 0.0 mm apart")
    assert report.text().splitlines()[-1].endswith("; the table fails: it cannot be audited as it is")
    copied_tower = np.concatenate([q, q[:1]], axis=0)  # a fourth tower copied from the first
    report = _audit(tmp_path, copied_tower)
    assert report.failed and report.problem.startswith("towers 1 and 4 stand 0.0 mm apart")
    reversed_heights = q[:, ::-1].copy()
    report = _audit(tmp_path, reversed_heights)
    assert report.failed and report.problem.startswith("the table's levels step 31.") and \
        "mm down: height 1 (Q[tower][0]) must be the bottom block" in report.problem
    assert report.suspects == ()  # the above poses are judged against the top of the stacks all the same
    above = q.copy()
    above[2, 0, ABOVE] = q[2, 0, ON]
    (suspect,) = _audit(tmp_path, above).suspects
    assert "mm below the table's top level (less than 5 mm over it" in suspect.reason
    assert suspect.reason.endswith("it holds the joint values of tower 3 height 1 on: a copied entry")


def test_missing_entries_are_listed_and_the_rest_used(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    q = rt.recorded_like(rt.stacked_station(rng), rng).q
    missing = [(0, 2, ON), (1, 0, ABOVE), (2, 1, ABOVE)]
    report = _audit(tmp_path, q, missing=missing)
    assert [(e.tower, e.height, e.k) for e in report.missing] == missing
    assert report.points_used == 8 and report.suspects == ()
    assert "missing (3 of 18, not used): tower 1 height 3 on, tower 2 height 1 above, tower 3 height 2 above" in \
        report.text()


def test_too_little_left_to_fit_says_what_is_needed(tmp_path: Path) -> None:
    q = rt.recorded_q(load_station("lab_real"), None)
    with pytest.raises(TaughtPointsError, match=r"too little left to fit the grid: it needs a usable contact \('on'\) "
                                                r"pose on every tower \(3 towers\).*tower\(s\) 3 have none"):
        _audit(tmp_path, q, missing=[(2, h, k) for h in range(3) for k in (ON, ABOVE)])


def test_shared_above_over_a_flat_layout_is_flagged(tmp_path: Path) -> None:
    # On the flat simulator layout "heights" are rows 0.10 m apart: one above pose per tower is over one row only.
    st = load_station("lab_sim")
    report = _audit(tmp_path, rt.shared_above(st, _exact(st)), "sim_pos")
    flagged = {(s.tower, s.height, s.k) for s in report.suspects}
    assert flagged == {(t, h, ABOVE) for t in range(3) for h in range(2)}
    assert all("the above pose shared by heights 1, 2, 3 of tower" in s.reason and "off its contact's vertical line"
               in s.reason for s in report.suspects)
    assert report.shared_above == ((0, (0, 1, 2)), (1, (0, 1, 2)), (2, (0, 1, 2)))


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
    for e in report.entries:  # the measured point and the calibration's, as a plot draws them
        if e.status != "missing":
            target = T_world_tcp(lab_real, e.tower, e.height, e.k).translation
            assert np.allclose(e.fitted_m, target, atol=1e-12)
            assert 1e3 * math.dist(e.point_m, e.fitted_m) == pytest.approx(e.error_mm, abs=1e-9)


def test_json_has_the_documented_shape_and_every_threshold(tmp_path: Path) -> None:
    rng = np.random.default_rng(8)
    q, _, _ = swapped_towers(rt.stacked_station(rng), rng)
    doc = json.loads(json.dumps(_audit(tmp_path, q, missing=[(0, 0, ABOVE)]).to_json()))
    assert set(doc) == {"entries", "suspects", "warnings", "fit"}
    assert len(doc["entries"]) == 18
    for e in doc["entries"]:
        assert {"tower", "height", "pose", "error_mm", "off_line_mm", "off_level_mm", "over_top_mm", "tilt_deg",
                "status", "reason", "point_m", "fitted_m"} <= set(e)
        assert e["status"] in ("ok", "warn", "suspect", "unchecked", "missing")
        assert (e["error_mm"] is None) == (e["status"] == "missing") == (e["point_m"] is None)
        assert (e["off_level_mm"] is None) == (e["pose"] == "above" or e["status"] == "missing")
    assert [(e["tower"], e["height"], e["pose"]) for e in doc["entries"][:3]] == [(1, 1, "on"), (1, 1, "above"),
                                                                                  (1, 2, "on")]
    assert len(doc["suspects"]) == 2 and all("swapped towers" in s["reason"] for s in doc["suspects"])
    suspect_slots = {(s["tower"], s["height"], s["pose"]) for s in doc["suspects"]}
    assert suspect_slots == {(e["tower"], e["height"], e["pose"]) for e in doc["entries"] if e["status"] == "suspect"}
    fit = doc["fit"]
    assert fit["points_used"] == 7 and fit["layout"] == "stacked" and fit["threshold_mm"] == 8.0
    r = fit["rule"]
    assert r["contact"]["never_flagged_within_mm"] == 5.0 and r["contact"]["never_flagged_within_deg"] == 4.0
    assert r["contact"]["flagged_over_mm"] == 8.0 and r["contact"]["flagged_over_deg"] == 5.0
    assert 5.0 <= r["contact"]["warn_over_mm"] <= 8.0 and 4.0 <= r["contact"]["warn_over_deg"] <= 5.0
    assert r["above"] == {"accepted_over_top_mm": 10.0, "accepted_within_line_mm": 8.0,
                          "flagged_under_top_or_contact_mm": 5.0, "flagged_off_line_mm": 10.0, "tilt_judged": False}
    assert r["heading_judged"] is False and r["sigma_mm"] > 0


# ------------------------------------------------------------------------------------------------------- CLI


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    rc = main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


def test_cli_fit_exit_codes_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rng = np.random.default_rng(9)
    q = rt.recorded_like(rt.stacked_station(rng), rng).q
    clean = rt.write_table(tmp_path / "clean.yaml", "real_pos", rt.table_doc(q, contact_only=True))
    rc, out, err = _run(["check-table", str(clean), "--key", "real_pos", "--fit"], capsys)
    assert rc == 0 and err == ""
    assert "missing (9 of 18, not used)" in out and "rule: a contact within 5 mm of its tower's line" in out
    bad = rt.write_table(tmp_path / "bad.yaml", "real_pos", rt.table_doc(rt.typo(q, (0, 1, ON), 0, 10.0)))
    rc, out, err = _run(["check-table", str(bad), "--key", "real_pos", "--fit", "--json"], capsys)
    assert rc == 1 and err == ""
    doc = json.loads(out)
    assert out.count("\n") == 1
    assert (doc["suspects"][0]["tower"], doc["suspects"][0]["height"], doc["suspects"][0]["pose"]) == (1, 2, "on")
    assert "likely a typo in joint 1 (base)" in doc["suspects"][0]["reason"]


def test_cli_fit_tolerances_replace_the_flag_thresholds(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    st = load_station("lab_real")
    path = rt.write_table(tmp_path / "t.yaml", "real_pos",
                          rt.table_doc(_moved(st, _exact(st), (1, 1, ON), (0.0, 0.0, 3.0))))
    assert _run(["check-table", str(path), "--key", "real_pos", "--fit"], capsys)[0] == 0
    rc, out, _ = _run(["check-table", str(path), "--key", "real_pos", "--fit", "--tol-mm", "2", "--json"], capsys)
    doc = json.loads(out)
    assert rc == 1 and doc["fit"]["rule"]["fixed"] is True and doc["fit"]["rule"]["contact"]["flagged_over_mm"] == 2
    assert [(s["tower"], s["height"]) for s in doc["suspects"]] == [(2, 2)]


def test_cli_fit_uses_the_key_s_default_base_or_the_given_one(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    assert default_base("sim_pos") == "lab_sim" and default_base("real_pos") == "lab_real"
    sim = load_station("lab_sim")
    path = rt.write_table(tmp_path / "t.yaml", "sim_pos", rt.table_doc(generate_table(sim).q))
    rc, out, _ = _run(["check-table", str(path), "--key", "sim_pos", "--fit"], capsys)
    assert rc == 0 and "robot base, tool and home of lab_sim" in out and "a flat layout\n" in out
    rc, out, _ = _run(["check-table", str(path), "--key", "sim_pos", "--fit", "--base", "lab_real"], capsys)
    assert rc == 0 and "robot base, tool and home of lab_real" in out and "audited as flat all the same" in out


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
