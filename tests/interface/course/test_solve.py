"""The lab program's solve (ur3hanoi.interface.course.solve): in world time against the simulated station (no ROS), and
end to end as ``ur3hanoi ros-solve`` against ``ur3hanoi ros-station`` over a real roscore (marked ``ros``)."""

from __future__ import annotations

import json
from collections.abc import Callable

import numpy as np
import pytest

from tests.support.ros_support import final_slots, free_port, requires_ros, ros_env, roscore, run, station, ur3hanoi_cmd
from ur3hanoi.errors import PuzzleError, SuctionFaultError
from ur3hanoi.interface.course.controller import Controller
from ur3hanoi.interface.course.solve import run_lab_solve
from ur3hanoi.sim.world import MoveJWorld
from ur3hanoi.tables.ik_table import generate_table


class SimArm:
    """The solver's Arm over Controller in world time: what RosArm does over ROS, without the wall clock."""

    def __init__(self, driver: Controller, v: float = 4.0, a: float = 4.0) -> None:
        self.driver, self.v, self.a = driver, v, a
        self.world = driver.world
        self.io = False
        self.dest = self.world.q
        self.calls: list[str] = []
        self.watched_moves = 0
        self.drop_on_watched_move: int | None = None  # remove the held block 0.1 s into this watched move

    def _cycle(self, watched: bool, cycles: int) -> None:
        if watched and self.watched_moves == self.drop_on_watched_move and cycles == 12:
            assert self.world.holding is not None
            assert self.world.remove(self.world.holding) == "dropped"
        self.driver.cycle()

    def move(self, q, watch: Callable[[], None] | None = None) -> None:
        self.calls.append("move")
        self.driver.submit(list(q), self.v, self.a, self.io)
        self.dest = np.array(q, dtype=float)
        self.watched_moves += watch is not None
        self.driver.cycle()
        for cycles in range(2000):
            if watch is not None:
                watch()
            if np.max(np.abs(self.world.q - self.dest)) < 5e-4:
                return
            self._cycle(watch is not None, cycles)
        raise AssertionError(f"never reached {q}")

    def suction(self, on: bool) -> None:
        self.calls.append(f"suction {'on' if on else 'off'}")
        self.io = on
        self.move(self.dest)
        self.calls.pop()

    def held(self) -> bool:
        return self.world.feedback().held

    def wait_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        t_end = self.world.time + timeout_s
        while not predicate():
            if self.world.time >= t_end:
                return False
            self.driver.cycle()
        return True

    def feedback_text(self) -> str:
        fb = self.world.feedback()
        return f"DIGIN={fb.digin}, AIN0={fb.ain0:.2f} V"


def slots(world: MoveJWorld) -> dict[int, tuple[int | None, int | None]]:
    return {b.block: (b.tower, b.height) for b in world.blocks()}


@pytest.mark.parametrize(("name", "start", "end"), [("lab_sim", 0, 2), ("lab_real", 1, 0)])
def test_solves_in_world_time(name, start, end, request):
    station = request.getfixturevalue(name)
    world = MoveJWorld(station, start, 3)
    driver = Controller(world)
    arm = SimArm(driver)
    result = run_lab_solve(arm, generate_table(station).q, station.q_home_array, start, end, 3)
    assert len(result.moves) == 7
    assert slots(world) == {0: (end, 0), 1: (end, 1), 2: (end, 2)}
    assert world.at_home() and not world.suction_on
    assert not driver.rejected and driver.summary()["max_settle_s"] < 0.1
    assert [c for c in arm.calls if c.startswith("suction")] == ["suction on", "suction off"] * 7


def test_missing_block_halts_suction_off_at_home(lab_sim):
    world = MoveJWorld(lab_sim, 0, 3, removed=1)
    arm = SimArm(Controller(world))
    with pytest.raises(SuctionFaultError) as err:
        run_lab_solve(arm, generate_table(lab_sim).q, lab_sim.q_home_array, 0, 2, 3)
    assert err.value.exit_code == 3
    assert str(err.value).startswith("suction fault in move 2/7: yellow block 2 is missing at tower 1 height 2 "
                                     "(DIGIN=0, AIN0=1.4")
    assert str(err.value).endswith("halted, suction off, arm returned home")
    assert arm.calls[-2:] == ["suction off", "move"]
    assert world.at_home() and not world.suction_on
    assert slots(world) == {0: (0, 0), 1: (None, None), 2: (2, 0)}


def test_block_dropped_during_the_carry_halts(lab_sim):
    world = MoveJWorld(lab_sim, 0, 3, drop_on_grasp=2)  # the third grasp: red, tower 3 -> tower 2
    arm = SimArm(Controller(world))
    with pytest.raises(SuctionFaultError, match="suction fault in move 3/7: red block 3 was dropped while carrying "
                                                "it from tower 3 to tower 2"):
        run_lab_solve(arm, generate_table(lab_sim).q, lab_sim.q_home_array, 0, 2, 3)
    assert world.at_home() and not world.suction_on and world.holding is None
    assert [e.kind for e in world.events].count("dropped") == 1


@pytest.mark.parametrize(("leg", "what"), [(1, "lift"), (2, "carry"), (3, "descent")])
def test_block_lost_in_any_leg_with_a_block_halts(lab_sim, leg, what):
    world = MoveJWorld(lab_sim, 0, 3)
    arm = SimArm(Controller(world))
    arm.drop_on_watched_move = 3 + leg  # move 2 (its watched moves are 4, 5, 6)
    with pytest.raises(SuctionFaultError, match="suction fault in move 2/7: yellow block 2 was dropped while "
                                                "carrying it from tower 1 to tower 2"):
        run_lab_solve(arm, generate_table(lab_sim).q, lab_sim.q_home_array, 0, 2, 3)
    assert world.at_home() and not world.suction_on, what


def test_bad_table_shape_is_refused(lab_sim):
    arm = SimArm(Controller(MoveJWorld(lab_sim, 0, 3)))
    with pytest.raises(PuzzleError, match=r"table shape \(3, 3, 6\) is invalid"):
        run_lab_solve(arm, np.zeros((3, 3, 6)), lab_sim.q_home_array, 0, 2, 3)


# ----------------------------------------------------------------------------------------- over ROS (real time)

SOLVE_TIMEOUT_S = 150.0
FAST = ("--v", "6.283", "--a", "8")  # the UR3 maximum: joints 1-3 are capped at pi rad/s, 4 rad/s^2 anyway


@pytest.mark.ros
@requires_ros
def test_ros_solve_two_start_end_pairs(tmp_path):
    env = ros_env(free_port(), tmp_path)
    with roscore(env), station(env, tmp_path) as st:
        first = run(ur3hanoi_cmd("ros-solve", "--start", "1", "--end", "3", "--json", *FAST), env, SOLVE_TIMEOUT_S)
        assert first.returncode == 0, first.stderr
        assert json.loads(first.stdout)["status"] == "solved"
        assert final_slots(st.snapshot()) == {1: (3, 1), 2: (3, 2), 3: (3, 3)}
        # The second pair starts where the first ended, from a table file and the real robot's command line.
        table = tmp_path / "lab2_data.yaml"
        assert run(ur3hanoi_cmd("tables", "lab_sim", "--key", "sim_pos", "-o", str(table)), env, 120).returncode == 0
        second = run(ur3hanoi_cmd("ros-solve", "--start", "3", "--end", "2", "--table", str(table), "--key",
                                  "sim_pos", *FAST), env, SOLVE_TIMEOUT_S)
        assert second.returncode == 0, second.stderr
        assert "solved: 7 moves, tower 3 -> 2" in second.stdout
        report = st.stop()
    assert final_slots(report) == {1: (2, 1), 2: (2, 2), 3: (2, 3)}
    final = report["final"]
    assert final["at_home"] and not final["suction_on"] and final["ready"]
    assert report["commands"]["rejected"] == 0
    assert [e["kind"] for e in report["suction_events"]].count("grasp") == 14


@pytest.mark.ros
@requires_ros
def test_ros_solve_halts_on_a_removed_block(tmp_path):
    env = ros_env(free_port(), tmp_path)
    with roscore(env), station(env, tmp_path, "--remove-block", "2") as st:
        result = run(ur3hanoi_cmd("ros-solve", "--start", "1", "--end", "3", *FAST), env, SOLVE_TIMEOUT_S)
        report = st.stop()
    assert result.returncode == 3, result.stderr
    assert result.stderr.strip().splitlines()[-1].startswith(
        "ur3hanoi: error: suction fault in move 2/7: yellow block 2 is missing at tower 1 height 2")
    final = report["final"]
    assert not final["suction_on"] and final["at_home"] and final["holding"] is None
    assert final_slots(report) == {1: (1, 1), 2: (None, None), 3: (3, 1)}
    assert report["faults"] == [{"t": 0.0, "kind": "removed", "block": 2, "colour": "yellow"}]
    assert report["suction_events"][-1]["kind"] == "suction_off"


@pytest.mark.ros
@requires_ros
def test_ros_solve_halts_when_the_block_drops_during_a_carry(tmp_path):
    env = ros_env(free_port(), tmp_path)
    with roscore(env), station(env, tmp_path, "--drop-on-grasp", "1") as st:
        result = run(ur3hanoi_cmd("ros-solve", "--start", "1", "--end", "3", *FAST), env, SOLVE_TIMEOUT_S)
        report = st.stop()
    assert result.returncode == 3, result.stderr
    assert ("suction fault in move 1/7: red block 3 was dropped while carrying it from tower 1 to tower 3"
            in result.stderr)
    assert [f["kind"] for f in report["faults"]] == ["dropped"]
    assert not report["final"]["suction_on"] and report["final"]["at_home"]
