#!/usr/bin/env python
"""UR's own ROS 2 example client, unmodified, against ``ur3hanoi ros2-station --driver ur`` (run with a real rclpy:
``ur3hanoi ros2-env``'s environment).

``upstream/ur_robot_driver_examples.py.txt`` is UniversalRobots/Universal_Robots_ROS2_Driver
``ur_robot_driver/examples/examples.py`` on branch jazzy @ e9499954614229f089a672b64cd63c1e2a49c328, byte for byte
(git blob 17b03a91635f6ea6006e1f07c92bcbb491b83658; BSD-3-Clause, its notice in the file). It is loaded as a module
(``examples``) and its ``Robot`` class used as its ``__main__`` block uses it: ``Robot(node)`` waits for
``/io_and_status_controller/set_io``, ``/dashboard_client/play``, ``/controller_manager/switch_controller`` and the
scaled and passthrough controllers' actions; ``send_trajectory`` and ``set_io``. Two deviations from that block,
both in what it is given, none in the client: ``send_trajectory`` gets the action client its signature asks for
(upstream's ``__main__`` leaves it out and raises TypeError), and the waypoints are offsets from the station's home
from where the arm is, to the station's home and 0.1 rad past it, 1 s apart (upstream's are "arbitrary joint
positions, change according to your own needs", 4 s apart).

Then the calls UR's integration tests make with the same services (``test/test_common.py`` @ 58792167,
``sjtc_trajectory_test``'s switch, ``DashboardInterface``'s play, stop and program_running, ``list_controllers``),
through ``Robot.call_service``. Prints one JSON line.

Usage: ur_examples_runner.py HOME_JSON
"""

import importlib.util
import json
import sys
from pathlib import Path

import rclpy
from builtin_interfaces.msg import Duration
from controller_manager_msgs.srv import ListControllers, SwitchController
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from ur_dashboard_msgs.srv import IsProgramRunning

UPSTREAM = Path(__file__).resolve().parent / "upstream" / "ur_robot_driver_examples.py.txt"


def load_examples():
    spec = importlib.util.spec_from_loader("examples", loader=None)
    module = importlib.util.module_from_spec(spec)
    exec(compile(UPSTREAM.read_text(encoding="utf-8"), "examples.py", "exec"), module.__dict__)
    return module


def main():
    home = json.loads(sys.argv[1])
    examples = load_examples()
    rclpy.init()
    node = Node("robot_driver_test")
    robot = examples.Robot(node)
    out = {"connected": True}
    for name, srv_type in (("/controller_manager/list_controllers", ListControllers),
                           ("/dashboard_client/stop", Trigger),
                           ("/dashboard_client/program_running", IsProgramRunning)):
        robot.service_clients[name] = examples.waitForService(node, name, srv_type)

    def listing():
        return {c.name: c.state for c in robot.call_service("/controller_manager/list_controllers",
                                                            ListControllers.Request()).controller}

    def trigger(name):
        r = robot.call_service(f"/dashboard_client/{name}", Trigger.Request())
        return [r.success, r.message]

    def running():
        r = robot.call_service("/dashboard_client/program_running", IsProgramRunning.Request())
        return [r.success, r.answer, r.program_running]

    def switch(activate, deactivate, strictness):
        r = robot.call_service("/controller_manager/switch_controller", SwitchController.Request(
            activate_controllers=activate, deactivate_controllers=deactivate, strictness=strictness))
        return [r.ok, r.message]

    def trajectory(client):
        state = {}
        sub = node.create_subscription(JointState, "/joint_states", lambda m: state.setdefault("q", m), 10)
        while "q" not in state:
            rclpy.spin_once(node, timeout_sec=0.1)
        node.destroy_subscription(sub)
        q = dict(zip(state["q"].name, state["q"].position, strict=False))
        here = [q[j] for j in examples.ROBOT_JOINTS]
        waypts = [here, home, [h - 0.1 for h in home]]
        try:
            return robot.send_trajectory(waypts, [Duration(sec=s) for s in (1, 2, 3)], client)
        except Exception as exc:  # the example raises when the goal is not accepted
            return str(exc)

    out["controllers"] = listing()
    out["play"] = trigger("play")
    out["trajectory"] = trajectory(robot.jtc_action_client)
    robot.set_io(1, 1.0)
    robot.set_io(1, 0.0)
    out["set_io"] = True
    # sjtc_trajectory_test's switch, the other way first: passthrough active, the scaled controller refuses goals.
    out["to_passthrough"] = switch(["passthrough_trajectory_controller"], ["scaled_joint_trajectory_controller"],
                                   SwitchController.Request.BEST_EFFORT)
    out["scaled_while_passthrough"] = trajectory(robot.jtc_action_client)
    out["both_position"] = switch(["joint_trajectory_controller", "scaled_joint_trajectory_controller"], [],
                                  SwitchController.Request.STRICT)
    out["back"] = switch(["scaled_joint_trajectory_controller"], ["passthrough_trajectory_controller"],
                         SwitchController.Request.STRICT)
    out["again"] = switch(["scaled_joint_trajectory_controller"], [], SwitchController.Request.STRICT)
    out["unknown"] = switch(["no_such_controller"], [], SwitchController.Request.STRICT)
    # The dashboard: stop the program, the controller_stopper deactivates the scaled controller; play brings it back.
    out["stop"] = trigger("stop")
    out["running_after_stop"] = running()
    out["controllers_after_stop"] = listing()
    out["trajectory_while_stopped"] = trajectory(robot.jtc_action_client)
    out["stop_again"] = trigger("stop")
    out["play_again"] = trigger("play")
    out["running_after_play"] = running()
    out["controllers_after_play"] = listing()
    out["trajectory_after_play"] = trajectory(robot.jtc_action_client)
    print(json.dumps(out), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
