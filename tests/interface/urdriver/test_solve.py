"""The plan on the UR driver, on the CPU clock: the neutral client (:func:`run_driver_solve`) against the neutral
station through the loopback transport -- a solve, its timing, the halts, the driver's errors, a far start, the
client's timeout under the speed slider."""

from __future__ import annotations

import re
from dataclasses import replace
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from tests.support.driver_helpers import goal, send, station
from ur3hanoi.errors import DriverError, SuctionFaultError
from ur3hanoi.interface.common.moves import describe_move
from ur3hanoi.interface.urdriver.client import DriverGoalError, DriverState
from ur3hanoi.interface.urdriver.facts import ErrorCode
from ur3hanoi.interface.urdriver.loopback import LoopbackTransport
from ur3hanoi.interface.urdriver.solve import DriverSolveConfig, run_driver_solve
from ur3hanoi.io.resources import station_file
from ur3hanoi.lifecycle import Terminated
from ur3hanoi.plan import Plan, PlanConfig, plan_solve


@cache
def plan(n_blocks: int) -> Plan:
    return plan_solve(station().station, 0, 2, n_blocks, PlanConfig())


def solve(n_blocks: int, transport_class=LoopbackTransport, config: DriverSolveConfig | None = None, **options):
    st = station(n_blocks=n_blocks, **options)
    tr = transport_class(st)
    tr.connect()
    lines: list[str] = []
    try:
        result = run_driver_solve(tr, plan(n_blocks), st.station.wiring, config, log=lines.append)
    except Exception as exc:
        exc.station, exc.lines = st, lines  # type: ignore[attr-defined]
        raise
    return result, st, lines


def slots(st) -> dict[int, tuple[int | None, int | None]]:
    return {b["block"]: (b["tower"], b["height"]) for b in st.report()["final"]["blocks"]}


def wired(tmp_path: Path, generator: str = "12") -> str:
    """lab_sim with a vacuum generator output, as a UR3e cell of ENME480 is wired (pin 12, the cup on DO 0 here)."""
    path = tmp_path / "wired.yaml"
    path.write_text(station_file("lab_sim").read_text() + f"io:\n  vacuum_generator_output: {generator}\n")
    return str(path)


def io_calls(st) -> list[tuple[int, float]]:
    return [(c["pin"], c["state"]) for c in st.report()["io_calls"]]


def test_a_three_block_solve_runs_the_plan_in_its_own_time(tmp_path):
    result, st, lines = solve(3, calibration=wired(tmp_path))
    p = plan(3)
    assert slots(st) == {1: (3, 1), 2: (3, 2), 3: (3, 3)}
    assert result.goals == 15 and result.approach_s == 0.0
    # The generator first (before anything moves), then one progress line per move, as the course interface's
    # solve prints them.
    assert lines == ["vacuum generator on: configurable output 4 (set_io pin 12) (calibration "
                     "io.vacuum_generator_output)"] + [f"move {i + 1}/7: {describe_move(mv)}"
                                                       for i, mv in enumerate(p.moves)] + \
        ["vacuum generator off: configurable output 4 (set_io pin 12)"]
    # ... and every output off at the end, the cup's first, as the bridge leaves the cell (the station logs the
    # last calls in its next cycle)
    st.cycle()
    calls = io_calls(st)
    assert calls[0] == (12, 1.0) and calls[-2:] == [(0, 0.0), (12, 0.0)] and calls.count((0, 1.0)) == 7
    assert st.report()["final"]["digital_outputs_on"] == []
    # The executed time is the plan's: one control cycle per goal more, the dwells as planned.
    assert result.executed_s == pytest.approx(p.duration_s, rel=0.02)
    report = st.report()
    assert report["goals"]["succeeded"] == 15 and report["goals"]["max_lateness_s"] <= 0.02
    assert report["final"]["at_home"] and not report["final"]["suction_on"]
    # The path the client measured, every joint state from the plan's start to its end (125 Hz on lab_sim): well
    # inside the plan's 2 mm corridor (measured 0.08 mm; the vertical legs 0.05 mm).
    path = result.path
    assert path is not None and path.samples == pytest.approx(125 * result.executed_s, abs=2)
    assert path.max_m < 0.25e-3 and path.vertical_max_m is not None and path.vertical_max_m < 0.1e-3


def test_at_half_speed_the_motion_takes_twice_as_long():
    result, st, _ = solve(1, speed_scaling=0.5)
    p = plan(1)
    assert slots(st)[1] == (3, 1)
    assert result.executed_s == pytest.approx(2 * p.motion_s + p.dwell_total_s, rel=0.02)
    assert result.path is not None and result.path.max_m < 0.25e-3


def test_a_missing_block_halts_cancel_suction_off_home():
    with pytest.raises(SuctionFaultError, match=r"move 1/7: red block 3 is missing at tower 1 height 3 \(DI0=0, "
                                                r"AI0=1\.4\d V\); halted, suction off, arm returned home") as err:
        solve(3, removed=2)
    report = err.value.station.report()  # type: ignore[attr-defined]
    assert report["final"]["at_home"] and not report["final"]["suction_on"]


def test_a_dropped_block_halts_within_one_control_cycle():
    with pytest.raises(SuctionFaultError, match="red block 3 was dropped while carrying it from tower 1 to tower 3") \
            as err:
        solve(3, drop_on_grasp=0)
    report = err.value.station.report()  # type: ignore[attr-defined]
    (halt,) = report["halts"]
    assert halt["cycles"] == 1  # io_states of cycle k says so; the cancel is handled in cycle k + 1
    assert report["goals"]["canceled"] == 1 and report["final"]["at_home"] and not report["final"]["suction_on"]


class HoldingTransport(LoopbackTransport):
    """Holds the arm 60 cycles into the first goal (an obstacle)."""

    def wait(self, timeout_s: float) -> None:
        if self.cycles == 60:
            self.station.on_hold(3.0)
        super().wait(timeout_s)


class HoldInCarry(LoopbackTransport):
    """Holds the arm for 0.1 s, 100 control cycles into the second goal (the carry of move 1): someone touching it.
    The controller's path tolerance (0.2 rad) lets it go on; the robot catches up on a short cut."""

    def wait(self, timeout_s: float) -> None:
        if self._sent == 2:
            self.in_carry = getattr(self, "in_carry", 0) + 1
            if self.in_carry == 100:
                self.station.on_hold(0.1)
        super().wait(timeout_s)


def test_an_arm_held_in_a_carry_leaves_the_corridor_and_the_client_measures_it():
    result, st, _ = solve(1, HoldInCarry)
    assert slots(st)[1] == (3, 1) and st.report()["goals"]["aborted"] == 0  # solved all the same
    assert result.path is not None and result.path.max_m > 5e-3 and result.path.worst_phase == "CARRY"


class RenamingTransport(LoopbackTransport):
    """Sends every goal with a joint the controller does not have."""

    def send_goal(self, g):
        return super().send_goal(replace(g, joint_names=(*g.joint_names[:5], "gripper_joint")))


def test_an_aborted_goal_ends_the_solve_with_the_drivers_code_suction_off():
    with pytest.raises(DriverGoalError, match=r"ended goal 1/3 \(approach of move 1\): aborted: "
                                              r"PATH_TOLERANCE_VIOLATED \(-4\) \(no error string\); suction off") as e:
        solve(1, HoldingTransport)
    assert e.value.result.code == ErrorCode.PATH_TOLERANCE_VIOLATED
    assert not e.value.station.world.suction_on  # type: ignore[attr-defined]


def test_a_rejected_goal_ends_the_solve_with_the_drivers_code():
    with pytest.raises(DriverGoalError, match=r"rejected goal 1/3 .*: rejected: INVALID_JOINTS \(-2\)"):
        solve(1, RenamingTransport)


class MovedFirst(LoopbackTransport):
    """The arm is 0.3 rad from home on joint 1 when the solve starts."""

    def connect(self) -> None:
        super().connect()
        q = self.station.world.q
        assert send(self, goal(q + np.array([0.3, 0, 0, 0, 0, 0]), 1.0, q))[0].status == "succeeded"


def test_an_arm_far_from_the_plans_start_is_brought_there_slowly_or_refused():
    result, st, lines = solve(1, MovedFirst)
    assert lines[0].startswith("the arm is 0.300 rad from where the plan starts (shoulder_pan_joint): moving there "
                               "first at 25 % speed")
    assert result.approach_s > 0.5 and slots(st)[1] == (3, 1)
    with pytest.raises(DriverError, match=r"the arm is 0\.300 rad from where the plan starts \(shoulder_pan_joint\): "
                                          r"expected within 0\.01 rad"):
        solve(1, MovedFirst, DriverSolveConfig(far_start="refuse"))


class FullSpeedLiar(LoopbackTransport):
    """Reports a speed scaling of 1 whatever the slider says."""

    def latest(self) -> DriverState:
        return replace(super().latest(), speed_scaling=1.0)


def test_the_clients_goal_timeout_counts_the_speed_scaling():
    result, st, _ = solve(1, config=DriverSolveConfig(goal_margin_s=0.5), speed_scaling=0.3)
    assert slots(st)[1] == (3, 1) and result.executed_s > 2.5 * plan(1).motion_s
    with pytest.raises(DriverError, match=r"goal 1/3 \(approach of move 1\) did not finish within \d+\.\d s of "
                                          r"trajectory time .*: canceled, suction off"):
        solve(1, FullSpeedLiar, DriverSolveConfig(goal_margin_s=0.5), speed_scaling=0.3)


def test_a_hand_recorded_tables_plan_runs_too():
    """``--table``: the plan through the table's waypoints (rest to rest, as the lab program moves) is cut at its
    dwells and run the same way."""
    from ur3hanoi.plan import plan_table
    from ur3hanoi.tables.ik_table import generate_table

    st = station(n_blocks=1)
    p = plan_table(st.station, generate_table(st.station).q, 0, 2, 1, PlanConfig())
    tr = LoopbackTransport(st)
    tr.connect()
    result = run_driver_solve(tr, p, st.station.wiring)
    assert slots(st) == {1: (3, 1)} and result.executed_s == pytest.approx(p.duration_s, rel=0.02)


@pytest.mark.parametrize(("client_generator", "named"), [
    (None, r"the calibration names no vacuum generator output \(io\.vacuum_generator_output\): if the cell switches "
           r"its generator from the robot \(ENME480's UR3e: set_io pin 12, configurable output 4\), write that pin "
           r"into io\.vacuum_generator_output$"),
    (11, r"with the vacuum generator's configurable output 3 \(set_io pin 11\) \(io\.vacuum_generator_output\) on "
         r"since the start: is that the generator's pin"),
])
def test_without_the_cells_generator_on_the_cup_does_not_pull_and_the_first_grasp_halts_naming_the_pin(
        tmp_path, client_generator, named):
    """The cell switches its vacuum generator on pin 12; the client's calibration names no generator, or pin 11."""
    st = station(n_blocks=1, calibration=wired(tmp_path))
    tr = LoopbackTransport(st)
    tr.connect()
    client = replace(st.station.wiring, generator=client_generator)
    with pytest.raises(SuctionFaultError) as err:
        run_driver_solve(tr, plan(1), client)
    message = str(err.value)
    assert re.match(r"suction fault in move 1/1: no vacuum at the grasp of green block 1 at tower 1 height 1 \(DI0=0, "
                    r"AI0=1\.0\d V, (DO11=1, )?DO0=1\); halted, suction off, arm returned home\. The cup's digital "
                    r"output 0 \(io\.suction_output\) is on but the vacuum sensor reads no vacuum", message), message
    assert re.search(named, message), message
    # nothing was picked (the block stands where it was spawned), the arm is home, every output is off
    st.cycle()
    assert slots(st)[1] == (1, 1) and st.report()["final"]["at_home"]
    assert st.report()["final"]["digital_outputs_on"] == [] and not st.world.suction_on


class StopMidCarry(LoopbackTransport):
    """0.2 s into the first carry (the block held): Ctrl-C, SIGTERM (raised as :class:`Terminated`) or the arm held
    against an obstacle (the controller aborts the goal: an error)."""

    def __init__(self, station, stop) -> None:
        super().__init__(station)
        self.stop, self.held_cycles = stop, 0

    def wait(self, timeout_s: float) -> None:
        super().wait(timeout_s)
        if self._sent == 2 and self.station.output.io.digital_in[0] and self.held_cycles < 25:
            self.held_cycles += 1
            if self.held_cycles == 25:
                self.stop(self.station)


def _hold(st) -> None:
    st.on_hold(3.0)


def _raise(kind):
    def stop(_st) -> None:
        raise kind
    return stop


@pytest.mark.parametrize(("stop", "raised"), [(_raise(KeyboardInterrupt), KeyboardInterrupt),
                                              (_raise(Terminated), Terminated), (_hold, DriverGoalError)],
                         ids=["ctrl-c", "sigterm", "error"])
def test_every_way_out_mid_carry_stops_the_arm_and_switches_every_output_off(tmp_path, stop, raised):
    st = station(n_blocks=1, calibration=wired(tmp_path))
    tr = StopMidCarry(st, stop)
    tr.connect()
    lines: list[str] = []
    with pytest.raises(raised):
        run_driver_solve(tr, plan(1), st.station.wiring, log=lines.append)
    # what the way out did, said (an aborted goal has ended and the error path has switched the cup off already)
    assert lines[-1] == "stopping: " + ("configurable output 4 (set_io pin 12) off" if raised is DriverGoalError else
                                        "the running goal canceled, digital output 0 off, configurable output 4 "
                                        "(set_io pin 12) off")
    st.cycle()
    report = st.report()
    assert tr.held_cycles == 25 and io_calls(st)[0] == (12, 1.0) and io_calls(st)[-2:] == [(0, 0.0), (12, 0.0)]
    assert report["goals"]["canceled" if raised is not DriverGoalError else "aborted"] == 1
    assert report["final"]["digital_outputs_on"] == [] and not st.world.suction_on
    assert not st.report()["final"]["goal_active"] and float(np.max(np.abs(st.world.qd))) < 1e-2  # stopped


def test_a_stopped_robot_program_refuses_the_solve_before_any_goal():
    with pytest.raises(DriverError, match=r"^the robot program is not running \(robot_program_running is false on "
                                          r"the loopback station\): .*; start the External Control program on the "
                                          r"pendant$") as err:
        solve(1, program_stop_at_s=0.0)
    assert err.value.station.report()["goals"]["received"] == 0  # type: ignore[attr-defined]


def test_a_program_stopped_mid_solve_ends_it_exit_3_suction_off_the_arm_where_it_was():
    from ur3hanoi.errors import ProgramStoppedError
    from ur3hanoi.interface.urdriver.profile import ROS1_SCALED, ROS2_SCALED

    p = plan(1)
    carry = p.duration_s / 2  # in the carry of the one block: the suction is on
    for profile, how in ((ROS1_SCALED, r"preempted \(.*\)"),
                         (ROS2_SCALED, r'aborted: INVALID_GOAL \(-1\) "Current goal cancelled during deactivate '
                                       r'transition\."')):
        with pytest.raises(ProgramStoppedError, match=r"^the External Control program stopped on the robot during "
                                                      r"goal \d/3 \(\w+ of move 1\) \(robot_program_running false; "
                                                      rf"the controller: {how}\): the arm stopped where it was, "
                                                      r"suction off; .*run again$") as err:
            solve(1, program_stop_at_s=carry, profile=profile)
        st = err.value.station  # type: ignore[attr-defined]
        st.cycle()  # the set_io queued last takes effect in the next control cycle
        assert err.value.exit_code == 3 and not st.world.suction_on
        assert st.world.time == pytest.approx(carry, abs=0.6)  # ended at the stop, not after a timeout
        assert not st.report()["final"]["at_home"] and st.report()["goals"]["received"] == 2
