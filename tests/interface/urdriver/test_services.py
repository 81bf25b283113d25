"""The dashboard and controller_manager calls answered by the station's control thread (CPU clock, no middleware):
play and stop change the program as the pendant does, the controllers and the follower follow."""

from __future__ import annotations

from tests.support.driver_helpers import goal, send, station
from ur3hanoi.interface.urdriver.facts import ErrorCode
from ur3hanoi.interface.urdriver.loopback import LoopbackTransport
from ur3hanoi.interface.urdriver.profile import ROS2_SCALED
from ur3hanoi.interface.urdriver.services import ServiceCall, controller_rows

SCALED, PASS = "scaled_joint_trajectory_controller", "passthrough_trajectory_controller"


def call(st, tr, kind: str, *args):
    c = ServiceCall(kind, *args)
    st.on_service(c)
    tr.wait(0.0)  # the next control cycle answers it
    return c.wait(0.0)


def test_dashboard_and_switches_drive_the_program_the_controllers_and_the_goals():
    st = station(profile=ROS2_SCALED, initial_controller=SCALED)
    tr = LoopbackTransport(st)
    tr.connect()
    home = st.station.q_home_array
    h = tr.send_goal(goal(home + 0.2, 2.0))
    for _ in range(20):
        tr.wait(0.0)
    assert call(st, tr, "stop") == (True, "Stopped")
    assert h.done() and h.result().error_string == "Current goal cancelled during deactivate transition."
    assert not st.output.program_running and call(st, tr, "running") == (True, "Program running: false", False)
    assert call(st, tr, "stop") == (False, "Failed to execute: Stop")
    assert send(tr, goal(home, 1.0))[0].status == "rejected"
    assert call(st, tr, "play") == (True, "Starting program") and st.output.program_running
    rows = {r["name"]: r for r in controller_rows(call(st, tr, "list"))}
    assert rows[SCALED]["state"] == "active" and len(rows[SCALED]["claimed_interfaces"]) == 6
    assert call(st, tr, "switch", [PASS], [SCALED], 2) == (True, "")
    assert st.controllers.trajectory_controller() == PASS
    r, _ = send(tr, goal(home, 1.0))  # the follower runs for the passthrough controller now
    assert r.status == "succeeded" and r.code == ErrorCode.SUCCESSFUL
    assert st.report()["final"]["controllers"][PASS] == "active"
