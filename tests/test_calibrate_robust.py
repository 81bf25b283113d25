"""The robust fit: thresholds from the data's scatter, a start that gross errors cannot drag, at most half left out."""

from __future__ import annotations

import math

import numpy as np
import pytest

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
from ur3hanoi.grid import ON
from ur3hanoi.station import Station

from . import recorded_tables as rt

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
