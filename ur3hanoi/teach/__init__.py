"""``ur3hanoi teach``: teach the station on the robot, not on paper.

A guided terminal session records the contact poses the arm's driver publishes (the course's real driver,
``ros-station`` or ``ros2-station``) into a taught-points file, checks every point as soon as it is taught, and
ends with the calibration, the lab table and the next command (the command line, :mod:`ur3hanoi.cli.teach`).

Module map (one concept each):

- :mod:`~ur3hanoi.teach.driver`: what teach needs from a driver client (a protocol; no middleware here).
- :mod:`~ur3hanoi.teach.stillness`: is the arm still (no joint moved more than 0.05 deg in 0.5 s)?
- :mod:`~ur3hanoi.teach.taught_file`: the session's taught-points file, written atomically at every record.
- :mod:`~ur3hanoi.teach.advice`: which pose to record next, and why (the audit's ``unchecked`` rule).
- :mod:`~ur3hanoi.teach.feedback`: every point's distance from where the others put it and the point that is
  wrong (the calibration's own judgement, :mod:`ur3hanoi.calibrate.consensus`), after each record.
- :mod:`~ur3hanoi.teach.jog`: Cartesian jog steps by closed-form IK, refused with their reason.
- :mod:`~ur3hanoi.teach.session`: the session's state and actions (record, undo, skip, jog...).
- :mod:`~ur3hanoi.teach.terminal`: keys without Enter and a live status in a plain terminal.
- :mod:`~ur3hanoi.teach.interactive`: the keys and the loop of the terminal session.
- :mod:`~ur3hanoi.teach.ur_driver`: on the official UR driver (``--driver ur``): the program's state, jog goals
  refused while it is stopped, the suction key.

This package sits beside the transports (it imports none of them): the command line connects a driver client
(:class:`ur3hanoi.interface.course.client.TopicArm`) and passes it in.
"""
