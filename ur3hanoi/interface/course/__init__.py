"""The course protocol's core, middleware-neutral: what a lab program's topics carry (``ur3/command``,
``ur3/position``, ``ur3/gripper_input``; on ROS 2 the bridge's ``ur3e/*``). Modules, one concept each (importing
this package needs neither ROS nor MuJoCo):

Station side:

- :mod:`~ur3hanoi.interface.course.station`: :class:`~ur3hanoi.interface.course.station.CourseStation`, the
  station without its transport (a :class:`~ur3hanoi.interface.common.station.ServerCore` whose arm moves by
  ``movej``).
- :mod:`~ur3hanoi.interface.course.controller`: the UR controller's command FIFO, ``isReady`` and the settle
  measurements (:class:`~ur3hanoi.interface.course.controller.Controller`); each move runs on
  :class:`ur3hanoi.sim.MoveJWorld` through the servo law ``ur3hanoi solve`` uses.
- :mod:`~ur3hanoi.interface.course.command`: which command messages the station executes or refuses.

Client side:

- :mod:`~ur3hanoi.interface.course.client`: the move-and-wait and suction feedback over three topics,
  :class:`~ur3hanoi.interface.course.client.TopicArm` (errors: :class:`ur3hanoi.errors.DriverError`).
- :mod:`~ur3hanoi.interface.course.solve`: the lab program's solve with suction checks and halt
  (:func:`~ur3hanoi.interface.course.solve.run_lab_solve`).

Bindings: :mod:`ur3hanoi.interface.ros1` (``server``, ``client``) and :mod:`ur3hanoi.interface.ros2`.
"""
