"""``teach --driver ur``: the options and the connection of teach on the official UR driver (the session itself is
:class:`ur3hanoi.teach.ur_driver.UrTeacher` on :class:`ur3hanoi.interface.urdriver.cell.DriverArm`)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ur3hanoi.interface.urdriver.cell import CellLink
    from ur3hanoi.station.calibration import Station
    from ur3hanoi.teach.driver import DriverNames

DRIVER_HELP = ("course (default): the course's topics (ur3/position, ur3/command; ur3e/* on ROS 2); ur: the official "
               "UR driver (ur_robot_driver, or ros-station/ros2-station --driver ur): records /joint_states by joint "
               "name, jogs by short goals to the scaled trajectory controller while the External Control program "
               "runs, v switches the suction through set_io and reads it back from io_states")


def add_teach_driver_options(p: argparse.ArgumentParser) -> None:
    """``--driver`` and ``--ros-distro`` (teach and check-arm)."""
    from ur3hanoi.cli.driver import DRIVERS
    from ur3hanoi.cli.ros2 import add_distro_option

    p.add_argument("--driver", choices=DRIVERS, default="course", help=DRIVER_HELP)
    add_distro_option(p)


def cell_link(args: argparse.Namespace) -> CellLink:
    """The official driver's link of ``--via`` (not connected)."""
    if args.via == "ros":
        from ur3hanoi.interface.ros1.ur_cell import RosCellLink

        return RosCellLink(args.master, args.wait)
    from ur3hanoi.cli.ros2 import _distro
    from ur3hanoi.interface.ros2.rclpy_env import import_rclpy
    from ur3hanoi.interface.ros2.ur_cell import RclpyCellLink

    import_rclpy()  # say what is missing before anything else
    return RclpyCellLink(_distro(args), args.domain_id, args.network, args.wait)


def connect_ur(args: argparse.Namespace, base: Station) -> tuple[Any, DriverNames]:
    """teach's driver on the official UR driver, connected, and how messages name it."""
    from ur3hanoi.interface.urdriver.cell import DriverArm
    from ur3hanoi.teach.ur_driver import ur_names

    link = cell_link(args)
    try:
        link.connect()
    except BaseException:
        link.close()
        raise
    return DriverArm(link, base), ur_names(link.where, args.via)
