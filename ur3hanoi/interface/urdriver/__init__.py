"""The official Universal Robots drivers' interface, middleware-neutral: what a stand-in serves and a client sends.

Modules, one concept each (importing this package needs neither ROS nor MuJoCo):

- :mod:`~ur3hanoi.interface.urdriver.facts`: names, error codes, the IO pin mapping.
- :mod:`~ur3hanoi.interface.urdriver.profile`: the controllers' defaults and the ROS 1 / ROS 2 differences.
- :mod:`~ur3hanoi.interface.urdriver.spline`: the joint trajectory controller's linear, cubic and quintic segments.
- :mod:`~ur3hanoi.interface.urdriver.goal`: a ``FollowJointTrajectory`` goal and the checks before it is accepted.
- :mod:`~ur3hanoi.interface.urdriver.follower`: the scaled joint trajectory controller (goals, time, tolerances).
"""
