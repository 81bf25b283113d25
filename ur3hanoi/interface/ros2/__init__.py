"""The ROS 2 course interface (UMD ENME480 ``ur3e_mrc_msgs``) without a ROS installation, on Cyclone DDS.

- :mod:`~ur3hanoi.interface.ros2.msgs`: the messages as DDS IDL types, their ``.msg`` text and RIHS01 type hashes.
- :mod:`~ur3hanoi.interface.ros2.dds`: a ROS 2 node made of one Cyclone DDS participant (loopback-only by default, ROS
  2's
  default QoS, type hashes in USER_DATA, the node announced on ``ros_discovery_info``).
- :mod:`~ur3hanoi.interface.ros2.server`: ``ros2-station``, the MuJoCo station as the course bridge.
- :mod:`~ur3hanoi.interface.ros2.client`: ``ros2-solve``'s arm, driven by
  :func:`ur3hanoi.interface.course.solve.run_lab_solve`.

The world, command checks, motion, suction, the station's loop and report and the client's move-and-wait are the
middleware-free :mod:`ur3hanoi.interface`, shared with the ROS 1 binding :mod:`ur3hanoi.interface.ros1`; only the
transport differs.
"""
