"""The UR driver station on the CPU clock (the neutral core through the loopback transport): the robot under the
scaled controller -- on time, slowed and late, held, canceled, preempted, slowed by the slider -- its IO, its
report."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from tests.support.driver_helpers import goal, run_until, send, station
from ur3hanoi.interface.urdriver.facts import (
    CONTROLLER_JOINTS,
    FUN_SET_ANALOG_OUT,
    FUN_SET_DIGITAL_OUT,
    FUN_SET_FLAG,
    ErrorCode,
)
from ur3hanoi.interface.urdriver.loopback import LoopbackTransport


@pytest.fixture(scope="module")
def home() -> np.ndarray:
    return station().station.q_home_array


def fresh(**options):
    st = station(**options)
    tr = LoopbackTransport(st)
    tr.connect()
    return st, tr


def test_a_goal_runs_on_time_and_succeeds(home):
    st, tr = fresh()
    result, cycles = send(tr, goal(home + 0.5, 2.0, home))
    assert (result.status, result.code, result.error_string) == ("succeeded", 0, "")
    assert cycles == pytest.approx(250, abs=2)  # 2.0 s at 125 Hz, one cycle to accept
    np.testing.assert_allclose(st.world.q, home + 0.5, atol=2e-3)
    rec = st.report()["goal_records"][-1]
    assert rec["accepted"] and rec["result"] == "SUCCESSFUL (0)" and rec["lateness_s"] <= 0.02
    assert rec["max_path_error_rad"] < 0.02 and rec["min_speed_scaling"] == 1.0


def test_joint_order_and_rejections_with_the_drivers_codes(home):
    st, tr = fresh()
    reversed_names = tuple(reversed(CONTROLLER_JOINTS))
    assert send(tr, goal(home + 0.1, 0.5, home, names=reversed_names))[0].status == "succeeded"
    np.testing.assert_allclose(st.world.q, home + 0.1, atol=2e-3)
    r, n = send(tr, goal(home, 1.0, names=CONTROLLER_JOINTS[:5]))
    assert (r.status, r.code, n) == ("rejected", ErrorCode.INVALID_JOINTS, 1)
    bad_times = goal(home, 1.0, home)
    bad_times = type(bad_times)(bad_times.joint_names, tuple(reversed(bad_times.points)))
    r, _ = send(tr, bad_times)
    assert r.code == ErrorCode.INVALID_GOAL and "strictly increasing" in r.error_string
    counts = st.report()["goals"]
    assert (counts["accepted"], counts["rejected"]) == (1, 2)


def test_a_too_fast_trajectory_is_slowed_and_ends_late(home):
    """The UR driver's integration test: positions only, every joint 1 rad in 0.5 s. Slowed, it succeeds within the
    default goal time and fails with a 0.01 s one (doc/controllers.md: "If a trajectory is given with time
    constraints and the trajectory is slowed down during execution, the action fails")."""
    st, tr = fresh()
    r, n = send(tr, goal(home - 1.0, 0.5, home, fields=1))
    assert r.status == "succeeded" and n * 0.008 > 0.5 + 0.1
    st, tr = fresh()
    r, _ = send(tr, goal(home - 1.0, 0.5, home, fields=1, goal_time_tolerance_s=0.01))
    assert (r.status, r.code) == ("aborted", ErrorCode.GOAL_TOLERANCE_VIOLATED)
    # Too fast for the joint speed limits (quintic, peak 3.1 rad/s at joint 1): the robot scales itself down.
    st, tr = fresh()
    peak = np.zeros(6)
    r, n = send(tr, goal(home + 1.0, 0.6, home), each=lambda k: np.maximum(peak, np.abs(st.world.qd), out=peak))
    rec = st.report()["goal_records"][-1]
    assert r.status == "succeeded" and rec["min_speed_scaling"] < 0.7 and rec["lateness_s"] > 0.1
    assert np.all(peak <= np.asarray(st.station.limits.v_max) * 1.1)


def test_an_arm_held_off_its_path_aborts_with_path_tolerance(home):
    st, tr = fresh()
    r, _ = send(tr, goal(home + 1.0, 2.0, home), each=lambda k: st.on_hold(5.0) if k == 40 else None)
    assert (r.status, r.code, r.error_string) == ("aborted", ErrorCode.PATH_TOLERANCE_VIOLATED, "")
    assert st.report()["goal_records"][-1]["max_path_error_rad"] > 0.2


def test_cancel_stops_within_the_deceleration_limit_and_holds(home):
    st, tr = fresh()
    h = tr.send_goal(goal(home + np.array([2.0, -0.4, -0.6, 0.8, 1.2, 1.2]), 1.5, home))
    run_until(tr, lambda: np.max(np.abs(st.world.qd)) > 2.4, 200)
    h.cancel()
    qds = []
    run_until(tr, h.done, 5)
    assert h.result().status == "canceled"
    for _ in range(180):
        tr.wait(0.0)
        qds.append(st.world.qd)
    acc = np.abs(np.diff(np.array(qds), axis=0)) / 0.008
    assert np.all(acc.max(axis=0) <= np.asarray(st.station.limits.a_max) * 1.25)  # the ramp's, plus servo ripple
    assert np.max(np.abs(qds[-1])) < 1e-3  # at rest, holding
    q_rest = st.world.q
    for _ in range(20):
        tr.wait(0.0)
    np.testing.assert_allclose(st.world.q, q_rest, atol=1e-4)


def test_a_new_goal_preempts_and_the_arm_continues_smoothly(home):
    st, tr = fresh()
    first = tr.send_goal(goal(home + 1.0, 2.0, home))
    for _ in range(100):
        tr.wait(0.0)
    qds = [st.world.qd]
    second = tr.send_goal(goal(home - 0.2, 2.0, st.world.q))
    n = run_until(tr, second.done, 400, each=lambda k: qds.append(st.world.qd))
    assert first.result().status == "preempted" and second.result().status == "succeeded" and n > 200
    acc = np.abs(np.diff(np.array(qds), axis=0)) / 0.008
    assert acc.max() < 40.0  # no velocity jump at the switch (the bridge from the desired state)


def test_the_speed_slider_slows_the_trajectory_and_is_published(home):
    st, tr = fresh(speed_scaling=0.5)
    assert st.output.speed_scaling == 0.5
    r, cycles = send(tr, goal(home + 0.5, 2.0, home))
    assert r.status == "succeeded" and cycles == pytest.approx(500, abs=3)


def test_set_io_on_the_pins_the_driver_serves(home):
    st, tr = fresh()
    pin = st.station.wiring.output
    assert tr.set_io(FUN_SET_DIGITAL_OUT, pin, 1.0)
    assert not st.output.io.digital_out[pin] and not st.world.suction_on  # queued: applied by the next cycle
    tr.wait(0.0)
    assert st.output.io.digital_out[pin] and st.world.suction_on
    for fun, p, state, ok in ((FUN_SET_DIGITAL_OUT, 17, 1.0, True), (FUN_SET_DIGITAL_OUT, 18, 1.0, False),
                              (FUN_SET_DIGITAL_OUT, -1, 1.0, False), (FUN_SET_FLAG, 0, 1.0, False),
                              (FUN_SET_ANALOG_OUT, 1, 0.5, True), (FUN_SET_ANALOG_OUT, 1, 2.0, False),
                              (7, 0, 1.0, False)):
        assert tr.set_io(fun, p, state) == ok, (fun, p, state)
    tr.wait(0.0)
    io = st.output.io
    assert io.digital_out[17] and io.analog_out[1][1] == 0.5
    assert len(io.digital_in) == len(io.digital_out) == 18 and len(io.analog_in) == len(io.analog_out) == 2
    calls = st.report()["goals"]
    assert (calls["io_calls"], calls["io_refused"]) == (3, 5)


def test_io_states_read_the_suction_on_the_calibrations_pins(tmp_path):
    from ur3hanoi.io.resources import station_file

    cal = tmp_path / "wired.yaml"
    cal.write_text(station_file("lab_sim").read_text() + "io:\n  suction_output: 3\n  vacuum_switch_input: 5\n"
                   "  vacuum_sensor_input: 1\n")
    st, tr = fresh(calibration=str(cal))
    profile = st.world.cup.profile
    tr.wait(0.0)
    assert st.output.io.analog_in[1][1] == pytest.approx(profile.ain0_off, abs=0.05)
    assert st.output.io.analog_in[0][1] == 0.0
    tr.set_io(FUN_SET_DIGITAL_OUT, 0, 1.0)  # another output: the suction stays off
    tr.wait(0.0)
    assert not st.world.suction_on
    tr.set_io(FUN_SET_DIGITAL_OUT, 3, 1.0)
    tr.wait(0.0)
    tr.wait(0.0)
    assert st.world.suction_on and not st.output.io.digital_in[5]  # on, nothing held: the switch reads 0
    assert st.output.io.analog_in[1][1] == pytest.approx(profile.ain0_free, abs=0.05)


def test_the_cup_pulls_only_while_the_cells_vacuum_generator_is_on(tmp_path):
    """A cell wired as ENME480's UR3e: the generator on pin 12 (configurable output 4), the cup on its own output."""
    from ur3hanoi.io.resources import station_file

    cal = tmp_path / "generator.yaml"
    cal.write_text(station_file("lab_sim").read_text() + "io:\n  vacuum_generator_output: 12\n")
    st, tr = fresh(calibration=str(cal))
    profile = st.world.cup.profile
    tr.set_io(FUN_SET_DIGITAL_OUT, 0, 1.0)  # the cup's output alone: open to the air, no vacuum
    tr.wait(0.0)
    tr.wait(0.0)
    assert st.output.io.digital_out[0] and not st.world.suction_on
    assert st.output.io.analog_in[0][1] == pytest.approx(profile.ain0_off, abs=0.05)
    tr.set_io(FUN_SET_DIGITAL_OUT, 12, 1.0)
    tr.wait(0.0)
    tr.wait(0.0)
    assert st.world.suction_on and st.output.io.analog_in[0][1] == pytest.approx(profile.ain0_free, abs=0.05)
    assert st.report()["final"]["digital_outputs_on"] == [0, 12]
    assert st.report()["driver"]["wiring"]["vacuum_generator_output"] == 12
    tr.set_io(FUN_SET_DIGITAL_OUT, 12, 0.0)  # the generator off: the vacuum goes, whatever the cup's output says
    tr.wait(0.0)
    tr.wait(0.0)
    assert not st.world.suction_on and st.report()["final"]["digital_outputs_on"] == [0]


def test_a_stopped_robot_program_preempts_the_goal_and_refuses_new_ones(home):
    st, tr = fresh()
    h = tr.send_goal(goal(home + 0.5, 2.0, home))
    for _ in range(50):
        tr.wait(0.0)
    st.on_program(False)
    tr.wait(0.0)
    assert h.done() and h.result().status == "preempted"
    r, _ = send(tr, goal(home, 1.0, st.world.q))
    assert (r.status, r.code, r.error_string) == ("rejected", ErrorCode.INVALID_GOAL, "")  # goalCB: no text
    st.on_program(True)
    assert send(tr, goal(home, 1.0, st.world.q))[0].status == "succeeded"
    assert st.report()["final"]["program_running"]


def test_the_program_stops_and_runs_again_at_the_times_given_and_the_states_go_on(home):
    st, tr = fresh(program_stop_at_s=0.1, program_resume_at_s=0.3)
    seen = []
    for _ in range(60):  # 0.48 s at 125 Hz
        tr.wait(0.0)
        seen.append((st.output.t_s, st.output.program_running))
    stopped = [t for t, running in seen if not running]
    again = next(t for t, running in seen if running and t > stopped[0])
    assert 0.1 <= stopped[0] <= 0.1 + 2 * 0.008 and 0.3 <= again <= 0.3 + 2 * 0.008  # within its control cycle
    assert all(b[0] > a[0] for a, b in itertools.pairwise(seen))  # joint states and io_states go on
    assert [e["running"] for e in st.report()["program"]] == [False, True]
    st, tr = fresh(program_stop_at_s=0.0)  # stopped from the start: the first output says so
    assert not st.output.program_running
