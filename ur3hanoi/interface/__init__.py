"""The transports: what a lab program talks to (the server: ur3hanoi's MuJoCo arm behind the course's topics) and
the client that drives a driver (the course's, on the real arm, or the server), independent of the middleware.

The ROS 1 binding (:mod:`ur3hanoi.interface.ros1`, rospy) and the ROS 2 binding (:mod:`ur3hanoi.interface.ros2`,
Cyclone DDS) share everything here and add only their transport; they never import each other. Nothing in this
package imports rospy or a DDS library; importing it imports nothing heavy (MuJoCo only with the simulated arm,
:class:`ur3hanoi.sim.MoveJWorld`). The command line still calls a server a "station" (``ros-station``): the word is
the lab's; in the code a station is the calibrated layout (:mod:`ur3hanoi.station`).

Server side:

- :mod:`~ur3hanoi.interface.server`: :class:`~ur3hanoi.interface.server.ServerCore`, the node without its
  transport: options, the control cycle, the report.
- :mod:`~ur3hanoi.interface.controller`: the UR controller's command FIFO, ``isReady`` and the settle
  measurements (:class:`~ur3hanoi.interface.controller.Controller`); each move runs on
  :class:`ur3hanoi.sim.MoveJWorld` through the servo law ``ur3hanoi solve`` uses.
- :mod:`~ur3hanoi.interface.command`: which command messages the server executes or refuses.
- :mod:`~ur3hanoi.interface.inbox`: what the transport's threads hand to the control loop, bounded.
- :mod:`~ur3hanoi.interface.realtime`: the real-time schedule, its lag and the stop signals.
- :mod:`~ur3hanoi.interface.render`: ``--frames``/``--video`` of a server in a separate low-priority process.
- :mod:`~ur3hanoi.interface.lograte`: log lines a flood cannot multiply (one per topic and second, with counts).
- :mod:`~ur3hanoi.interface.errors`: :class:`~ur3hanoi.interface.errors.CommandError`.

The official UR driver's interface (``--driver ur``), middleware-neutral as well: :mod:`ur3hanoi.interface.urdriver`
(the scaled trajectory controller, IO, the station on :class:`~ur3hanoi.interface.server.ServerCore`, the plan as
goals and the client's solve); the bindings' ``ur_*`` modules serve and drive it.

Client side:

- :mod:`~ur3hanoi.interface.client`: the move-and-wait and suction feedback over three topics,
  :class:`~ur3hanoi.interface.client.TopicArm` (errors: :class:`ur3hanoi.errors.DriverError`).
- :mod:`~ur3hanoi.interface.solve`: the lab program's solve with suction checks and halt (:func:`run_lab_solve`).
"""
