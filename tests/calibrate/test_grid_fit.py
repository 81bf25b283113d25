"""The grid model: design, least squares, closed-form leave-one-out deviations (checked against refits)."""

from __future__ import annotations

import numpy as np
import pytest

from ur3hanoi.calibrate.grid_fit import (
    GridModel,
    choose_model,
    circular_mean,
    default_height_step,
    leave_one_out,
    measure,
    removable,
    solve,
)
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON, T_world_tcp
from ur3hanoi.tables.ik_table import generate_table

FULL = [(t, h, k) for t in range(3) for h in range(3) for k in (ON, ABOVE)]


def _noisy_points(station: Station, slots: list[tuple[int, int, int]], seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    exact = np.array([T_world_tcp(station, *s).translation for s in slots])
    return exact + rng.normal(scale=0.002, size=exact.shape)


def test_measure_gives_the_grid_of_a_generated_table(lab_real: Station) -> None:
    q = generate_table(lab_real).q
    m = measure(lab_real, [q[s] for s in FULL])
    exact = np.array([T_world_tcp(lab_real, *s).translation for s in FULL])
    np.testing.assert_allclose(m.p_world, exact, atol=1e-9)
    np.testing.assert_allclose(m.tilt_deg, 0.0, atol=1e-5)
    assert circular_mean(m.heading) == pytest.approx(lab_real.tool_yaw, abs=1e-9)


def test_exact_points_give_the_station_back(lab_real: Station) -> None:
    model = choose_model(lab_real, FULL)
    assert model == GridModel(3, (0, 1, 2), True)
    sol = solve(lab_real, model, FULL, np.array([T_world_tcp(lab_real, *s).translation for s in FULL]))
    np.testing.assert_allclose(sol.origins, lab_real.tower_origins, atol=1e-12)
    np.testing.assert_allclose(sol.step, lab_real.height_step, atol=1e-12)
    assert sol.approach == pytest.approx(lab_real.approach, abs=1e-12)
    np.testing.assert_allclose(sol.points(FULL), [sol.point(s) for s in FULL], atol=0)


def test_model_choice_follows_what_the_points_determine(lab_real: Station, lab_sim: Station) -> None:
    bottoms = [(t, 0, ON) for t in range(3)]
    assert choose_model(lab_real, bottoms) == GridModel(3, (), False)
    assert choose_model(lab_sim, [*bottoms, (0, 2, ON)]) == GridModel(3, (0, 1), False)  # flat: step is horizontal
    assert choose_model(lab_real, [(t, 0, ABOVE) for t in range(3)]) is None
    assert choose_model(lab_real, bottoms[:2]) is None
    np.testing.assert_allclose(default_height_step(lab_real, None), [0, 0, lab_real.block_size])


@pytest.mark.parametrize("seed", [0, 1])
def test_leave_one_out_equals_the_refit_without_the_point(lab_real: Station, seed: int) -> None:
    p = _noisy_points(lab_real, FULL, seed)
    model = choose_model(lab_real, FULL)
    assert model is not None
    loo, removable = leave_one_out(model, FULL, p, solve(lab_real, model, FULL, p))
    assert removable.all()
    for i in (0, 7, 17):
        rest = [s for j, s in enumerate(FULL) if j != i]
        refit = solve(lab_real, model, rest, np.delete(p, i, axis=0))
        np.testing.assert_allclose(loo[i], p[i] - refit.point(FULL[i]), atol=1e-12)


def test_a_point_the_fit_needs_cannot_be_left_out(lab_real: Station) -> None:
    slots = [(0, 0, ON), (0, 2, ON), (1, 0, ON), (1, 1, ON), (2, 1, ON)]  # tower 3 has one point only
    p = _noisy_points(lab_real, slots, 3)
    model = choose_model(lab_real, slots)
    assert model is not None
    loo, can = leave_one_out(model, slots, p, solve(lab_real, model, slots, p))
    assert can.tolist() == [True, True, True, True, False]
    assert np.isnan(loo[4]).all() and np.isfinite(loo[:4]).all()
    assert removable(model, slots).tolist() == can.tolist()  # from the slots alone, as teach's advice asks it


def test_one_point_per_tower_leaves_every_point_unchecked(lab_real: Station) -> None:
    slots = [(0, 2, ON), (1, 0, ON), (2, 0, ON)]
    model = choose_model(lab_real, slots)
    assert model is not None and not removable(model, slots).any()
    both = [*slots, (0, 0, ON), (1, 2, ON), (2, 2, ON)]
    model = choose_model(lab_real, both)
    assert model is not None and removable(model, both).all()
