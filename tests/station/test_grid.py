"""Tower grid: world poses of the lab's simulator layout and the stacked example, frame conversions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import (
    ABOVE,
    ON,
    R_world_tcp_down,
    T_base_tcp,
    T_world_tcp,
    block_center_world,
    block_xy_pos,
    grid_targets_world,
    table_z,
)


def test_lab_sim_grid_matches_lab_facts(lab_sim: Station) -> None:
    for t in range(3):
        for h in range(3):
            on = T_world_tcp(lab_sim, t, h, ON)
            above = T_world_tcp(lab_sim, t, h, ABOVE)
            assert on.translation == pytest.approx([0.40 - 0.10 * h, 0.05 + 0.10 * t, 0.0125], abs=1e-12)
            assert above.translation - on.translation == pytest.approx([0, 0, 0.096], abs=1e-12)
            # Tool straight down, TCP x along world +y (yaw +90 deg).
            assert on.rotation[:, 2] == pytest.approx([0, 0, -1], abs=1e-12)
            assert on.rotation[:, 0] == pytest.approx([0, 1, 0], abs=1e-12)


def test_lab_sim_blocks_rest_on_the_ground(lab_sim: Station) -> None:
    assert table_z(lab_sim) == pytest.approx(0.0, abs=1e-12)
    assert block_center_world(lab_sim, 1, 2) == pytest.approx([0.20, 0.15, 0.0159], abs=1e-12)
    assert block_xy_pos(lab_sim)[2][0] == pytest.approx([0.40, 0.25], abs=1e-12)


def test_base_frame_targets(lab_sim: Station) -> None:
    # Robot base at world (-0.15, 0.15, 0.01), unrotated: world (0.40, 0.05, 0.0125) is base (0.55, -0.10, 0.0025).
    T = T_base_tcp(lab_sim, 0, 0, ON)
    assert T.translation == pytest.approx([0.55, -0.10, 0.0025], abs=1e-12)


def test_stacked_heights_are_vertical(lab_real: Station) -> None:
    for h in range(1, 3):
        d = T_world_tcp(lab_real, 1, h, ON).translation - T_world_tcp(lab_real, 1, h - 1, ON).translation
        assert d == pytest.approx([0, 0, lab_real.block_size], abs=1e-12)
    # Suction point 3 mm below the top face at contact.
    top = block_center_world(lab_real, 0, 0)[2] + lab_real.block_size / 2
    assert top - T_world_tcp(lab_real, 0, 0, ON).translation[2] == pytest.approx(0.003, abs=1e-12)


@pytest.mark.parametrize("yaw", [0.0, 0.7, math.pi / 2, -2.5])
def test_down_rotation_is_proper_and_heads_along_yaw(yaw: float) -> None:
    R = R_world_tcp_down(yaw)
    assert pytest.approx(np.eye(3), abs=1e-12) == R.T @ R
    assert np.linalg.det(R) == pytest.approx(1.0)
    assert R[:, 0] == pytest.approx([math.cos(yaw), math.sin(yaw), 0.0], abs=1e-12)
    assert R[:, 2] == pytest.approx([0, 0, -1.0], abs=1e-12)


def test_grid_targets_shape(shipped_station: Station) -> None:
    poses = grid_targets_world(shipped_station)
    assert poses.shape == (shipped_station.n_towers, shipped_station.n_heights, 2, 4, 4)


@pytest.mark.parametrize(("tower", "height", "k", "match"), [(3, 0, 0, "tower index 3"), (0, -1, 0, "height index"),
                                                                (0, 0, 2, "pose index 2")])
def test_out_of_grid_index(lab_sim: Station, tower: int, height: int, k: int, match: str) -> None:
    with pytest.raises(Ur3HanoiError, match=match):
        T_world_tcp(lab_sim, tower, height, k)
