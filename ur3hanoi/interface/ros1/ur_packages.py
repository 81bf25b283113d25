"""The ROS 1 message packages UR's own clients import, written by genpy from the official texts: ``control_msgs``
(the trajectory action), ``controller_manager_msgs`` (list, load and switch controllers), ``cartesian_control_msgs``
(imported by ``ur_robot_driver/scripts/test_move``), ``std_srvs`` (``Trigger``) and ``ur_dashboard_msgs``
(``IsProgramRunning``).

Debian packages none of them. :func:`write_ur_packages` writes them as importable packages (``from
controller_manager_msgs.srv import SwitchController``), each module the text ``catkin_make`` would generate
(genpy's ``msg_generator`` and ``srv_generator``, actions expanded as ``genaction`` does), so a client written for the
driver runs unmodified with that folder on ``PYTHONPATH``. :func:`service_classes` are the station's own classes of
the services it serves (generated in memory, like :mod:`~ur3hanoi.interface.ros1.driver_msgs`).
"""

from __future__ import annotations

import importlib
import re
from functools import cache
from pathlib import Path
from typing import Any

from ur3hanoi.interface.ros1.driver_msgs import FJT, _split_full_text, action_texts, generate, ros1_text
from ur3hanoi.interface.ros1.env import ensure_driver_python
from ur3hanoi.interface.urdriver.facts import msg_text

CARTESIAN = "cartesian_control_msgs/FollowCartesianTrajectory"
MESSAGES: dict[str, tuple[str, str]] = {
    "controller_manager_msgs/ControllerState": ("controller_manager_msgs", "ControllerState-ros1.msg"),
    "controller_manager_msgs/HardwareInterfaceResources": ("controller_manager_msgs",
                                                           "HardwareInterfaceResources-ros1.msg"),
    "cartesian_control_msgs/CartesianPosture": ("cartesian_control_msgs", "CartesianPosture-ros1.msg"),
    "cartesian_control_msgs/CartesianTolerance": ("cartesian_control_msgs", "CartesianTolerance-ros1.msg"),
    "cartesian_control_msgs/CartesianTrajectory": ("cartesian_control_msgs", "CartesianTrajectory-ros1.msg"),
    "cartesian_control_msgs/CartesianTrajectoryPoint": ("cartesian_control_msgs", "CartesianTrajectoryPoint-ros1.msg"),
}
"""The plain messages: type -> vendored text (package, file)."""
SERVICES: dict[str, tuple[str, str]] = {
    "controller_manager_msgs/ListControllers": ("controller_manager_msgs", "ListControllers-ros1.srv"),
    "controller_manager_msgs/SwitchController": ("controller_manager_msgs", "SwitchController-ros1.srv"),
    "controller_manager_msgs/LoadController": ("controller_manager_msgs", "LoadController-ros1.srv"),
    "std_srvs/Trigger": ("std_srvs", "Trigger.srv"),
    "ur_dashboard_msgs/IsProgramRunning": ("ur_dashboard_msgs", "IsProgramRunning.srv"),
}
"""The services: type -> vendored text."""


def _texts() -> dict[str, str]:
    """Every message's text: ours, the actions' expansions, and what they depend on from Debian's classes."""
    texts: dict[str, str] = {}
    for module, name in (("trajectory_msgs.msg", "JointTrajectory"), ("actionlib_msgs.msg", "GoalStatus"),
                         ("actionlib_msgs.msg", "GoalID"), ("geometry_msgs.msg", "Pose"),
                         ("geometry_msgs.msg", "Twist"), ("geometry_msgs.msg", "Accel")):
        cls = getattr(importlib.import_module(module), name)
        texts.update(_split_full_text(cls._type, cls._full_text))
    texts.update(action_texts(FJT, ros1_text(FJT)))
    texts["control_msgs/JointTolerance"] = ros1_text("control_msgs/JointTolerance")
    texts.update(action_texts(CARTESIAN, msg_text("cartesian_control_msgs", "FollowCartesianTrajectory-ros1.action")))
    texts.update({t: msg_text(*where) for t, where in MESSAGES.items()})
    return texts


def package_sources() -> dict[str, str]:
    """``pkg/msg/_Name.py`` (and ``srv``) -> the module genpy generates, for every message and service written."""
    ensure_driver_python()
    msg_loader = importlib.import_module("genmsg.msg_loader")
    generator = importlib.import_module("genpy.generator")
    context = msg_loader.MsgContext.create_default()
    texts = _texts()
    specs = {t: msg_loader.load_msg_from_string(context, text, t) for t, text in texts.items()}
    for t, spec in specs.items():
        context.register(t, spec)
    ours = ("control_msgs/", "cartesian_control_msgs/", "controller_manager_msgs/")
    out = {}
    for t, spec in specs.items():
        if t.startswith(ours):
            pkg, name = t.split("/")
            out[f"{pkg}/msg/_{name}.py"] = "\n".join(generator.msg_generator(context, spec, {})) + "\n"
    for t, where in SERVICES.items():
        spec = msg_loader.load_srv_from_string(context, msg_text(*where), t)
        pkg, name = t.split("/")
        out[f"{pkg}/srv/_{name}.py"] = "\n".join(generator.srv_generator(context, spec, {})) + "\n"
    return out


def write_ur_packages(root: Path) -> list[Path]:
    """Write the packages into ``root`` (``root/<pkg>/msg/_Name.py``, ``__init__`` files); the files written
    (replaced atomically; nothing else under ``root`` is touched)."""
    from ur3hanoi.io.atomic import atomic_write

    sources = package_sources()
    files: dict[Path, str] = {}
    for rel, text in sources.items():
        pkg, kind, module = rel.split("/")
        files[root / rel] = text
        files[root / pkg / "__init__.py"] = f'"""{pkg}: generated by ur3hanoi from the official texts."""\n'
        init = root / pkg / kind / "__init__.py"
        files[init] = files.get(init, "") + f"from .{module.removesuffix('.py')} import *\n"
    for path in files:
        path.parent.mkdir(parents=True, exist_ok=True)  # the package layout is ours to create
    for path, text in files.items():
        atomic_write(path, text)
    return list(files)


@cache
def service_classes() -> dict[str, Any]:
    """The station's classes of :data:`SERVICES` (type -> rospy service class: ``_type``, ``_md5sum``,
    ``_request_class``, ``_response_class``), generated in memory with the messages they use."""
    ensure_driver_python()
    msg_loader = importlib.import_module("genmsg.msg_loader")
    gentools = importlib.import_module("genmsg.gentools")
    deps = {t: msg_text(*MESSAGES[t]) for t in ("controller_manager_msgs/HardwareInterfaceResources",
                                                "controller_manager_msgs/ControllerState")}
    out = {}
    for t, where in SERVICES.items():
        text = msg_text(*where)
        context = msg_loader.MsgContext.create_default()
        for dep, dep_text in deps.items():
            context.register(dep, msg_loader.load_msg_from_string(context, dep_text, dep))
        md5 = gentools.compute_md5(context, msg_loader.load_srv_from_string(context, text, t))
        request, response = re.split(r"(?:^|\n)---\n", text, maxsplit=1)
        classes = generate({**deps, f"{t}Request": request, f"{t}Response": response})
        out[t] = type(t.split("/")[1], (), {"_type": t, "_md5sum": md5, "_request_class": classes[f"{t}Request"],
                                            "_response_class": classes[f"{t}Response"]})
    out["controller_manager_msgs/ControllerState"] = classes["controller_manager_msgs/ControllerState"]
    out["controller_manager_msgs/HardwareInterfaceResources"] = \
        classes["controller_manager_msgs/HardwareInterfaceResources"]
    return out
