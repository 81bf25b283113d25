"""The base's layout moved and turned as a whole: the fit recovers a station's turn and shift (its closed form is the
regularized cost's minimum), and a tower is placed where the layout fitted to the others puts it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur3hanoi.calibrate.layout import SHIFT_PRIOR_MM, SIGMA_MM, TURN_PRIOR_DEG, fit_layout, tower_place

# lab_real's tower origins [mm]: a row along y, unevenly spaced.
BASE = np.array([[250.0, -200.0, 28.8], [250.0, -90.0, 28.8], [250.0, 40.0, 28.8]])
PIVOT = BASE.mean(axis=0)


def moved(points: np.ndarray, turn_deg: float = 2.0, shift: tuple[float, float, float] = (5.0, -4.0, 1.0)
          ) -> np.ndarray:
    c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return (points - PIVOT) @ R.T + PIVOT + np.array(shift)


def brute_cost(a: np.ndarray, b: np.ndarray, theta: float) -> float:
    """The regularized cost at turn ``theta`` with its best shift, by its definition."""
    c, s = math.cos(theta), math.sin(theta)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    ra = (a - PIVOT) @ R.T + PIVOT
    w, lam = 1.0 / SIGMA_MM**2, 1.0 / SHIFT_PRIOR_MM**2
    shift = w * (b - ra).sum(axis=0) / (len(a) * w + lam)
    r = b - ra - shift
    return float(w * np.sum(r * r) + lam * shift @ shift + (math.degrees(theta) / TURN_PRIOR_DEG) ** 2)


def test_the_layout_fit_recovers_a_turn_and_a_shift() -> None:
    fit = fit_layout(BASE, moved(BASE), PIVOT)
    assert math.isclose(math.degrees(fit.theta), 2.0, abs_tol=0.1)  # the priors pull it a little towards zero
    assert np.allclose(fit.shift, (5.0, -4.0, 1.0), atol=0.5)
    assert np.allclose(fit.apply(BASE), moved(BASE), atol=0.5)


@pytest.mark.parametrize("seed", range(5))
def test_the_closed_form_is_the_cost_s_minimum(seed: int) -> None:
    rng = np.random.default_rng(seed)
    b = moved(BASE, float(rng.uniform(-10, 10)), tuple(rng.uniform(-30, 30, 3))) + rng.normal(0, 3, (3, 3))
    fit = fit_layout(BASE, b, PIVOT)
    assert fit.cost == pytest.approx(brute_cost(BASE, b, fit.theta), rel=1e-9, abs=1e-9)
    dense = np.radians(np.linspace(-45, 45, 90001))
    assert fit.cost <= min(brute_cost(BASE, b, t) for t in dense[::100]) + 1e-9
    assert brute_cost(BASE, b, fit.theta + 1e-4) >= fit.cost and brute_cost(BASE, b, fit.theta - 1e-4) >= fit.cost


def test_a_tower_is_placed_by_the_two_others() -> None:
    fitted = moved(BASE)
    for t in range(3):
        place = tower_place(BASE, fitted, t, [o for o in range(3) if o != t], PIVOT)
        assert place is not None and np.linalg.norm(place - fitted[t]) < 1.0


def test_with_one_other_tower_a_turn_within_the_prior_is_allowed() -> None:
    for turn, inside in ((2.0, True), (2 * TURN_PRIOR_DEG, False)):
        fitted = moved(BASE, turn)
        place = tower_place(BASE, fitted, 2, [0], PIVOT)
        assert place is not None
        assert (np.linalg.norm(place - fitted[2]) < 0.1) == inside
    fitted = moved(BASE)
    fitted[2] += (0.0, 15.0, 0.0)  # along the row: no turn hides it
    place = tower_place(BASE, fitted, 2, [1], PIVOT)
    assert place is not None and np.linalg.norm(place - fitted[2]) == pytest.approx(15.0, abs=0.5)
    fitted[2] += (0.0, -15.0, 12.0)  # in height: no turn hides it
    place = tower_place(BASE, fitted, 2, [1], PIVOT)
    assert place is not None and np.linalg.norm(place - fitted[2]) == pytest.approx(12.0, abs=0.5)


def test_no_other_tower_places_nothing() -> None:
    assert tower_place(BASE, moved(BASE), 0, [], PIVOT) is None
