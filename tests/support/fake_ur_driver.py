"""A stand-in for the official ROS 1 UR driver that refuses the work: ``ros-solve --driver ur``'s tests run against it.

``python tests/support/fake_ur_driver.py MODE LOG`` publishes ``/joint_states`` (alphabetical, the lab_sim home
pose), ``io_states`` and ``/speed_scaling_factor`` at 125 Hz, serves ``set_io`` (recording every call) and the
scaled controller's ``FollowJointTrajectory`` with Debian's ``actionlib.ActionServer``, answering every goal as the
driver does when it cannot follow it:

- ``reject``: rejected with INVALID_JOINTS and no error string (the ROS 1 controller's ``goalCB``);
- ``abort``: accepted, then after 0.1 s aborted with PATH_TOLERANCE_VIOLATED and the plain JTC's text
  ``shoulder_pan_joint path error 0.250000``.

It prints ``ready`` once everything is advertised and, on SIGINT/SIGTERM, writes the ``set_io`` calls to LOG (JSON).
"""

from __future__ import annotations

import json
import signal
import sys
import threading
import time
from typing import Any

from ur3hanoi.interface.ros1.driver_msgs import load_driver_messages
from ur3hanoi.interface.ros1.env import import_rospy
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ROS1, ROS1_JOINT_STATE_ORDER
from ur3hanoi.station.calibration import load_station


def main(mode: str, log: str) -> int:
    rospy, m = import_rospy(), load_driver_messages()
    import actionlib
    import sensor_msgs.msg
    import std_msgs.msg

    rospy.init_node("ur_hardware_interface", argv=[sys.argv[0]], disable_signals=True)
    calls: list[list[float]] = []
    stop = threading.Event()
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, lambda *_: stop.set())

    def on_goal(gh: Any) -> None:
        R = m.FollowJointTrajectoryResult
        if mode == "reject":
            gh.set_rejected(R(error_code=R.INVALID_JOINTS, error_string=""))
            return
        gh.set_accepted()
        threading.Timer(0.1, lambda: gh.set_aborted(R(error_code=R.PATH_TOLERANCE_VIOLATED,
                                                      error_string="shoulder_pan_joint path error 0.250000"))).start()

    server = actionlib.ActionServer(ROS1.follow_joint_trajectory, m.FollowJointTrajectoryAction, on_goal,
                                    lambda gh: gh.set_canceled(), auto_start=False)
    server.start()
    rospy.Service(ROS1.set_io, m.SetIO, lambda req: (calls.append([req.fun, req.pin, req.state]),
                                                     m.SetIO._response_class(success=True))[1])
    pubs = (rospy.Publisher(ROS1.joint_states, sensor_msgs.msg.JointState, queue_size=10),
            rospy.Publisher(ROS1.io_states, m.IOStates, queue_size=10),
            rospy.Publisher(ROS1.speed_scaling, std_msgs.msg.Float64, queue_size=10))
    home = dict(zip(CONTROLLER_JOINTS, load_station("lab_sim").q_home, strict=True))
    print("ready", flush=True)
    while not stop.is_set():
        pubs[0].publish(sensor_msgs.msg.JointState(name=list(ROS1_JOINT_STATE_ORDER),
                                                   position=[home[j] for j in ROS1_JOINT_STATE_ORDER]))
        pubs[1].publish(m.IOStates(digital_in_states=[m.Digital(pin=i, state=False) for i in range(18)],
                                   digital_out_states=[m.Digital(pin=i, state=False) for i in range(18)],
                                   analog_in_states=[m.Analog(pin=i, domain=1, state=1.05) for i in range(2)],
                                   analog_out_states=[m.Analog(pin=i, domain=1, state=0.0) for i in range(2)]))
        pubs[2].publish(std_msgs.msg.Float64(1.0))
        time.sleep(0.008)
    with open(log, "w") as f:
        json.dump({"set_io": calls}, f)
    rospy.signal_shutdown("done")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
