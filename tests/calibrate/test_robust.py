"""The robust fit: thresholds from the data's scatter, a start that gross errors cannot drag, at most half left out."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support import recorded_tables as rt
from ur3hanoi.calibrate.grid_fit import choose_model, measure
from ur3hanoi.calibrate.robust import (
    MAXWELL_MEDIAN,
    MIN_POINTS_FOR_SCALE,
    MIN_SUSPECT_DEG,
    MIN_SUSPECT_MM,
    SUSPECT_SIGMAS,
    RobustFit,
    robust_fit,
    robust_sigma,
    thresholds,
)
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON

CONTACTS = [(t, h, ON) for t in range(3) for h in range(3)]


def test_robust_sigma_of_gaussian_deviations() -> None:
    rng = np.random.default_rng(0)
    lengths = np.linalg.norm(rng.normal(scale=1.5, size=(4000, 3)), axis=1)
    assert robust_sigma(lengths) == pytest.approx(1.5, rel=0.03)
    # A quarter of gross errors barely moves it (the median ignores them).
    lengths[:1000] = 80.0
    assert robust_sigma(lengths) == pytest.approx(1.5, rel=0.25)
    assert math.isnan(robust_sigma(np.ones(MIN_POINTS_FOR_SCALE - 1)))
    median = float(np.median(np.linalg.norm(rng.normal(size=(200000, 3)), axis=1)))
    assert median == pytest.approx(MAXWELL_MEDIAN, rel=0.01)


def test_thresholds_floor_scale_and_fixed() -> None:
    few = thresholds(np.array([9.0, 9.0]), np.array([5.0, 5.0]))
    assert (few.mm, few.deg, few.derived) == (MIN_SUSPECT_MM, MIN_SUSPECT_DEG, True)
    wide = np.full(10, 2.0 * MAXWELL_MEDIAN)  # sigma 2 mm
    th = thresholds(wide, np.full(10, 0.1))
    assert th.mm == pytest.approx(SUSPECT_SIGMAS * 2.0) and th.deg == MIN_SUSPECT_DEG
    fixed = thresholds(wide, np.full(10, 0.1), tol_mm=1.0, tol_deg=0.5)
    assert (fixed.mm, fixed.deg, fixed.derived) == (1.0, 0.5, False)
    assert th.describe().startswith(f"{th.mm:.1f} mm / 2.0 deg = max(3 mm, 5 sigma) / max(2 deg, 5 sigma)")


def _fit_contacts(station: Station, q: np.ndarray) -> RobustFit:
    m = measure(station, [q[s] for s in CONTACTS])
    model = choose_model(station, CONTACTS)
    assert model is not None
    return robust_fit(station, model, CONTACTS, m, np.ones(len(CONTACTS), dtype=bool))


@pytest.mark.parametrize(("a", "b"), [((1, 0, ON), (1, 2, ON)), ((2, 0, ON), (2, 1, ON))], ids=["1-3", "1-2"])
def test_swapped_heights_of_a_contact_only_table_do_not_drag_the_fit(lab_real: Station, a: tuple[int, int, int],
                                                                     b: tuple[int, int, int]) -> None:
    # Least squares over all nine contacts turns that tower's share of the common step around: every point is
    # then ~40 mm off. The trimmed start and its tie-break (the towers' first slots line up) leave out the two.
    q = rt.swap(rt.recorded_q(lab_real, np.random.default_rng(21)), a, b)
    fit = _fit_contacts(lab_real, q)
    assert [CONTACTS[i] for i in np.flatnonzero(~fit.used)] == [a, b]
    assert np.max(fit.deviation_mm[fit.used]) < rt.NOISE_MM[1] + 2.0
    np.testing.assert_allclose(fit.solution.step, lab_real.height_step, atol=0.003)


def test_never_more_than_half_left_out(lab_real: Station) -> None:
    q = rt.recorded_q(lab_real, np.random.default_rng(22))
    for t in range(3):  # scramble every tower's first two heights: most points are wrong
        q = rt.typo(q, (t, 0, ON), 0, 15.0 * (t + 1))
        q = rt.typo(q, (t, 1, ON), 1, -12.0)
    fit = _fit_contacts(lab_real, q)
    assert int((~fit.used).sum()) <= (len(CONTACTS) - 1) // 2


def _with_typos(station: Station, seed: int, n_bad: int, contact_only: bool, degrees: tuple[float, float]
                ) -> tuple[np.ndarray, list[tuple[int, int, int]]]:
    rng = np.random.default_rng(seed)
    q = rt.recorded_q(station, rng)
    slots = [(t, h, k) for t in range(3) for h in range(3) for k in ((ON,) if contact_only else (ON, 1))]
    injected = [slots[i] for i in rng.choice(len(slots), n_bad, replace=False)]
    for s in injected:
        q = rt.typo(q, s, int(rng.integers(6)), float(rng.choice([-1, 1]) * rng.uniform(*degrees)))
    return q, injected


@pytest.mark.parametrize("seed", [100, 101, 107, 108])
def test_three_gross_errors_in_nine_contacts(lab_real: Station, seed: int) -> None:
    # A third of the points wrong: the scale must come from every point (in the fit or not), else the trimmed
    # start's closest points understate it and honest 3 mm points are left out too.
    q, injected = _with_typos(lab_real, seed, 3, True, (3.0, 12.0))
    fit = _fit_contacts(lab_real, q)
    left_out = sorted(CONTACTS[i] for i in np.flatnonzero(~fit.used))
    assert left_out == sorted(injected)
    assert np.all(fit.severity[~fit.used] > 1.0) and np.all(fit.severity[fit.used] <= 1.0)


@pytest.mark.parametrize(("seed", "n_bad", "contact_only"), [(200, 2, True), (200, 3, True), (200, 4, False),
                                                            (201, 2, True), (201, 3, True), (202, 4, False)])
def test_a_suspect_that_can_be_left_out_is_not_in_the_fit(lab_real: Station, seed: int, n_bad: int,
                                                          contact_only: bool) -> None:
    # Moderate errors (1.5-4 deg) sit near the thresholds: the fit that is kept must not contain a point it finds
    # suspect and could do without (the prune step), so the station is the fit of the agreeing points only.
    q, _ = _with_typos(lab_real, seed, n_bad, contact_only, (1.5, 4.0))
    slots = CONTACTS if contact_only else [(t, h, k) for t in range(3) for h in range(3) for k in (ON, 1)]
    m = measure(lab_real, [q[s] for s in slots])
    model = choose_model(lab_real, slots)
    assert model is not None
    fit = robust_fit(lab_real, model, slots, m, np.ones(len(slots), dtype=bool))
    assert not np.any(fit.used & fit.removable & (fit.severity > 1.0))


@pytest.mark.parametrize(("seed", "delta_deg"), [(2, 2.5), (6, 2.5), (13, 2.0), (13, 2.5)])
def test_a_tower_s_majority_wins_over_a_lone_wrong_point(lab_real: Station, seed: int, delta_deg: float) -> None:
    # A moderate typo in the middle contact of a tower: a trimmed start may keep that tower's wrong point alone
    # and leave out its two good neighbours (both fit a start exactly). Of the best starts, the one most points
    # agree with is kept: the two good ones, not the lone wrong one.
    q = rt.typo(rt.recorded_q(lab_real, np.random.default_rng(seed)), (1, 1, ON), 0, delta_deg)
    fit = _fit_contacts(lab_real, q)
    assert [CONTACTS[i] for i in np.flatnonzero(~fit.used)] == [(1, 1, ON)]
