"""What both protocols' cores (:mod:`ur3hanoi.interface.course`, :mod:`ur3hanoi.interface.urdriver`) use,
middleware-neutral. Modules, one concept each (importing this package needs neither ROS nor MuJoCo):

- :mod:`~ur3hanoi.interface.common.station`: :class:`~ur3hanoi.interface.common.station.ServerCore`, a station
  without its protocol and transport: options, the control cycle, the report, rendering.
- :mod:`~ur3hanoi.interface.common.inbox`: what the transport's threads hand to the control loop, bounded.
- :mod:`~ur3hanoi.interface.common.realtime`: the real-time schedule, its lag and the stop signals.
- :mod:`~ur3hanoi.interface.common.render`: ``--frames``/``--video`` of a station in a separate low-priority process.
- :mod:`~ur3hanoi.interface.common.lograte`: log lines a flood cannot multiply (one per topic and second, with
  counts).
- :mod:`~ur3hanoi.interface.common.moves`: how a solve names a move on its log (both protocols' solves print it).
- :mod:`~ur3hanoi.interface.common.errors`: :class:`~ur3hanoi.interface.common.errors.CommandError`.
"""
