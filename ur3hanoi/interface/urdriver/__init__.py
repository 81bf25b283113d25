"""The official Universal Robots drivers' interface, middleware-neutral: what a stand-in serves and a client sends.

Modules, one concept each (importing this package needs neither ROS nor MuJoCo):

- :mod:`~ur3hanoi.interface.urdriver.facts`: names, error codes, the IO pin mapping, the official message texts
  (the data folder ``msg_texts/``, read by both bindings).
- :mod:`~ur3hanoi.interface.urdriver.profile`: the controllers' defaults and the ROS 1 / ROS 2 differences.
- :mod:`~ur3hanoi.interface.urdriver.spline`: the joint trajectory controller's linear, cubic and quintic segments.
- :mod:`~ur3hanoi.interface.urdriver.goal`: a ``FollowJointTrajectory`` goal and the checks before it is accepted.
- :mod:`~ur3hanoi.interface.urdriver.follower`: the scaled joint trajectory controller (goals, time, tolerances).
- :mod:`~ur3hanoi.interface.urdriver.io`: ``set_io`` and ``io_states``.
- :mod:`~ur3hanoi.interface.urdriver.plan_goals`: a Ruckig plan as goals, cut at its suction dwells.
- :mod:`~ur3hanoi.interface.urdriver.records`: what the station's report records (goals, IO calls, halts).
- :mod:`~ur3hanoi.interface.urdriver.client`: what a client's binding provides (``DriverTransport``).
- :mod:`~ur3hanoi.interface.urdriver.station`: the station without its transport (``DriverStation``).
- :mod:`~ur3hanoi.interface.urdriver.solve`: the plan on the driver with the lab's checks (``run_driver_solve``).
- :mod:`~ur3hanoi.interface.urdriver.joint_record`: the joint states a client received, in bounded memory.
- :mod:`~ur3hanoi.interface.urdriver.path_deviation`: how closely the executed suction point followed the plan.
- :mod:`~ur3hanoi.interface.urdriver.loopback`: client and station in one process on the CPU clock.
- :mod:`~ur3hanoi.interface.urdriver.cell`: the driver before a solve: teach's driver (jog goals, the suction read
  back), the joint states of the last seconds.
- :mod:`~ur3hanoi.interface.urdriver.check`: the cell checked before its first move (``check-arm``).

Bindings: :mod:`ur3hanoi.interface.ros1` (``ur_server``, ``ur_client``, ``ur_cell``) and :mod:`ur3hanoi.interface.ros2`.
"""
