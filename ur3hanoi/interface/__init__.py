"""What a remote lab program talks to: the simulated station and the client that drives one, independent of the
middleware.

The ROS 1 binding (:mod:`ur3hanoi.interface.ros1`, rospy) and the ROS 2 binding (:mod:`ur3hanoi.interface.ros2`, Cyclone
DDS) share everything here and add only their transport. Nothing in this package imports rospy or a DDS library;
importing the package imports nothing heavy (MuJoCo only with the simulated arm, :class:`ur3hanoi.sim.MoveJWorld`).

- :mod:`~ur3hanoi.interface.errors`: the errors (:class:`~ur3hanoi.interface.errors.RosError`,
  :class:`~ur3hanoi.interface.errors.CommandError`).
- :mod:`~ur3hanoi.interface.command`: which command messages the station executes or refuses.
- the simulated arm is :class:`ur3hanoi.sim.MoveJWorld` (:mod:`ur3hanoi.sim.world`): ``movej`` profiles
  (:mod:`ur3hanoi.robot.movej`) through the servo law ``ur3hanoi solve`` uses.
- :mod:`~ur3hanoi.interface.controller`: the command FIFO, ``isReady`` and the settle measurements.
- :mod:`~ur3hanoi.interface.lograte`: log lines a flood cannot multiply (one per topic and second, with counts).
- :mod:`~ur3hanoi.interface.server`: the station node's scaffolding (options, bounded inbox, real-time loop,
  report, signals), :class:`~ur3hanoi.interface.server.StationCore`.
- :mod:`~ur3hanoi.interface.render`: ``--frames``/``--video`` of a station in a separate low-priority process.
- :mod:`~ur3hanoi.interface.client`: the client's move-and-wait and suction feedback over three topics,
  :class:`~ur3hanoi.interface.client.TopicArm`.
- :mod:`~ur3hanoi.interface.solve`: the lab program's solve with suction checks and halt (:func:`run_lab_solve`).
"""
