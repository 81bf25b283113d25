"""The station's command FIFO: refused commands never move the arm; isReady; the settle records."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur3hanoi.ros.driver import StationDriver
from ur3hanoi.ros.errors import CommandError
from ur3hanoi.ros.world import StationWorld
from ur3hanoi.waypoints import generate_table


@pytest.fixture
def driver(lab_sim) -> StationDriver:
    return StationDriver(StationWorld(lab_sim, 0, 3), max_queue=3)


def test_refused_commands_do_not_move_the_arm(driver, lab_sim):
    home = lab_sim.q_home_array
    bad = [([0.0] * 5, 4.0, 4.0), ([math.nan] * 6, 4.0, 4.0), ([9.0, *home[1:]], 4.0, 4.0), (list(home), 0.0, 4.0)]
    for dest, v, a in bad:
        with pytest.raises(CommandError):
            driver.submit(dest, v, a, True)
    for _ in range(100):
        driver.cycle()
    assert np.max(np.abs(driver.world.q - home)) < 1e-6
    assert not driver.world.suction_on and driver.executed == [] and driver.ready
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
