"""The transports: two protocols on two middlewares. What a lab program talks to (a station: ur3hanoi's MuJoCo arm
behind a protocol's topics) and the client that drives a driver (the course's, on the real arm, or a station).

The two protocols' cores, middleware-neutral, siblings that never import each other:

- :mod:`ur3hanoi.interface.course`: the course's topics (``ur3/command``, ``ur3/position``, ``ur3/gripper_input``
  and the ROS 2 bridge's ``ur3e/*``): the ``movej`` station, the command checks, the client
  (:class:`~ur3hanoi.interface.course.client.TopicArm`) and the lab program's solve.
- :mod:`ur3hanoi.interface.urdriver`: the official UR driver's interface (``--driver ur``): the scaled trajectory
  controller, IO, the station, the plan as goals and the client's solve.

What both use, in :mod:`ur3hanoi.interface.common`: the station's real-time loop without a protocol
(:class:`~ur3hanoi.interface.common.station.ServerCore`: options, inbox, control cycle, report, rendering), the
real-time schedule, the bounded inbox, rate-limited log lines, the rendering process, the command error and how a
move is named on the log.

The ROS 1 binding (:mod:`ur3hanoi.interface.ros1`, rospy) and the ROS 2 binding (:mod:`ur3hanoi.interface.ros2`,
Cyclone DDS for the course's topics, rclpy for the UR driver's) bind both protocols and add only their transport;
they never import each other. Nothing in the cores or ``common`` imports rospy or a DDS library; importing them
imports nothing heavy (MuJoCo only with the simulated arm). The command line still calls a server a "station"
(``ros-station``): the word is the lab's; the calibrated layout is :mod:`ur3hanoi.station`.

Layers (``pyproject.toml``): ``ros1 | ros2`` > ``course | urdriver`` > ``common``.
"""
