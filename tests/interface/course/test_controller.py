"""The station's command FIFO: refused commands never move the arm; isReady; the settle records."""

from __future__ import annotations

import contextlib
import math

import numpy as np
import pytest

from ur3hanoi.interface.common.errors import CommandError
from ur3hanoi.interface.course.controller import Controller
from ur3hanoi.sim.world import MoveJWorld
from ur3hanoi.tables.ik_table import generate_table


@pytest.fixture
def driver(lab_sim) -> Controller:
    return Controller(MoveJWorld(lab_sim, 0, 3), max_queue=3)


def test_refused_commands_do_not_move_the_arm(driver, lab_sim):
    home = lab_sim.q_home_array
    bad = [([0.0] * 5, 4.0, 4.0), ([math.nan] * 6, 4.0, 4.0), ([9.0, *home[1:]], 4.0, 4.0), (list(home), 0.0, 4.0)]
    for dest, v, a in bad:
        with pytest.raises(CommandError):
            driver.submit(dest, v, a, True)
    for _ in range(100):
        driver.cycle()
    assert np.max(np.abs(driver.world.q - home)) < 1e-6
    assert not driver.world.suction_on and not driver.executed and driver.ready
    assert [r.reason.split(" ")[0] for r in driver.rejected] == ["destination", "destination[0]", "destination[0]",
                                                                 "v"]


def test_commands_run_in_order_and_is_ready_only_at_rest(driver, lab_sim):
    Q = generate_table(lab_sim).q
    driver.submit(list(Q[1, 0, 1]), 4.0, 4.0, False)
    driver.submit(list(Q[1, 0, 0]), 4.0, 4.0, False)
    driver.submit(list(Q[1, 0, 0]), 4.0, 4.0, False)  # the lab's 5 s re-publish: a zero-length move
    with pytest.raises(CommandError, match="3 commands are already waiting"):
        driver.submit(list(Q[1, 0, 0]), 4.0, 4.0, False)
    ready = []
    for _ in range(round(3.0 / driver.world.config.period_s)):
        driver.cycle()
        ready.append(driver.ready)
    assert not any(ready[:10]) and ready[-1]
    assert len(driver.executed) == 3
    first, second, repeat = driver.executed
    assert first.t_start < second.t_start <= repeat.t_start
    assert repeat.duration_s == 0.0
    assert np.max(np.abs(driver.world.q - Q[1, 0, 0])) < 5e-4
    summary = driver.summary()
    assert summary["executed"] == 3 and summary["rejected"] == 1 and summary["queued"] == 0
    assert 0.0 <= summary["max_settle_s"] < 0.1
    assert summary["max_rest_error_rad"] < 1e-4


def test_lead_joint_speed_is_capped(driver, lab_sim):
    q1 = lab_sim.q_home_array.copy()
    q1[0] += 3.0
    driver.submit(list(q1), 10.0, 10.0, False)
    driver.cycle()
    move = driver.executed[0]
    assert move.lead_velocity == pytest.approx(math.pi)  # 180 deg/s, the UR3's base
    assert move.lead_acceleration == pytest.approx(4.0)


@pytest.mark.parametrize(("v", "a"), [(1e-9, 1e-9), (4.0, 1e-9), (1e-9, 4.0), (5e-324, 5e-324), (0.001, 0.001)])
def test_a_move_longer_than_the_cap_is_refused_and_the_next_command_runs(driver, lab_sim, v, a):
    """v = a = 1e-9 was accepted as a 5e8 s move and the station never moved again."""
    q1 = lab_sim.q_home_array.copy()
    q1[0] += 0.5
    with pytest.raises(CommandError, match=r"the move would take .* s at v = .*: expected at most 60 s"):
        driver.submit(list(q1), v, a, True)
    assert not driver.queue and driver.n_rejected == 1
    driver.submit(list(q1), 4.0, 4.0, False)
    for _ in range(round(1.0 / driver.world.config.period_s)):
        driver.cycle()
    assert driver.n_executed == 1 and np.max(np.abs(driver.world.q - q1)) < 5e-4 and driver.ready


def test_the_cap_allows_the_slowest_course_speed_and_huge_finite_values(driver, lab_sim):
    q1 = lab_sim.q_home_array.copy()
    q1[0] -= 5.0  # the base, 5 rad at v = a = 0.1: 51 s
    driver.submit(list(q1), 0.1, 0.1, False)
    driver.submit(list(lab_sim.q_home_array), 1e300, 1e300, False)  # capped at the UR3's limits
    assert len(driver.queue) == 2
    driver.cycle()
    assert driver.executed[0].duration_s == pytest.approx(5.0 / 0.1 + 1.0)
    assert driver.summary()["max_move_s"] == 60.0


def test_records_are_bounded_and_totals_count_every_command(lab_sim):
    """A flood of commands: the kept records and the summary's size do not grow with the number of commands."""
    driver = Controller(MoveJWorld(lab_sim, 0, 3), max_queue=5, records_kept=10)
    home = list(lab_sim.q_home_array)
    near = [home[0] + 0.01, *home[1:]]
    sent = 0
    for _ in range(400):
        for _ in range(3):
            with contextlib.suppress(CommandError):
                driver.submit(near if sent % 2 else home, 4.0, 4.0, False)
            sent += 1
        driver.cycle()
    s = driver.summary()
    assert s["executed"] + s["rejected"] + s["queued"] == sent
    assert s["executed"] > 10 and s["rejected"] > 10
    assert len(driver.executed) == 10 and len(driver.rejected) == 10
    assert s["max_error_after_settling_rad"] is not None and s["superseded_before_settling"] >= 0
