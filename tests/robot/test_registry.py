"""ur3hanoi.robot.registry: every description is usable, the UR3e's numbers are UR's published ones, and the UR URDF
layout built from a DH table reproduces example-robot-data's UR3 URDF (an independent file)."""

from __future__ import annotations

import math
from dataclasses import replace
from xml.etree import ElementTree

import pytest

from ur3hanoi.robot import model as ur3
from ur3hanoi.robot.registry import ROBOTS, UR3, UR3E, DHParameters, check_description, robot_description
from ur3hanoi.robot.urdf import ur_layout


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_every_registered_robot_is_valid(name: str) -> None:
    r = robot_description(name)
    assert r.name == name
    assert check_description(r) == []


def test_a_broken_description_is_reported() -> None:
    bad = replace(UR3E, dh=DHParameters(d=UR3E.dh.d, a=UR3E.dh.a, alpha=(0.0,) * 6), v_max=(1.0,) * 5)
    problems = check_description(bad)
    assert any("alpha" in p for p in problems) and any("v_max" in p for p in problems)
    with pytest.raises(KeyError, match="expected one of ur3, ur3e"):
        robot_description("ur5")


def test_ur3e_dh_is_urs_published_table() -> None:
    """../shared/lab/ros2-interface.md: d1 = 0.15185, a2 = -0.24355, a3 = -0.2132, d4 = 0.13105, d5 = 0.08535,
    d6 = 0.0921 m; 180/360 deg/s."""
    assert UR3E.dh.d == (0.15185, 0.0, 0.0, 0.13105, 0.08535, 0.0921)
    assert UR3E.dh.a == (0.0, -0.24355, -0.2132, 0.0, 0.0, 0.0)
    assert UR3E.v_max == pytest.approx([math.radians(180)] * 3 + [math.radians(360)] * 3, abs=1e-15)
    assert sum(UR3E.masses) == pytest.approx(8.7985, abs=1e-12)  # links only; the datasheet's 11.2 kg adds the base


def test_ur3_entry_is_the_module_constants() -> None:
    assert (UR3.dh.d, UR3.dh.a, UR3.dh.alpha) == (ur3.DH_D, ur3.DH_A, ur3.DH_ALPHA)
    assert ur3.JointLimits.for_robot(UR3) == ur3.JointLimits.ur3()


def test_ur_layout_of_the_ur3_table_is_example_robot_datas_urdf() -> None:
    root = ElementTree.parse(ur3.urdf_path()).getroot()
    joints = {j.get("name"): j for j in root.findall("joint")}
    for jp in ur_layout(UR3):
        j = joints[jp.name]
        origin = j.find("origin")
        assert origin is not None
        xyz = [float(v) for v in origin.get("xyz", "").split()]
        rpy = [float(v) for v in origin.get("rpy", "").split()]
        axis = [float(v) for v in j.find("axis").get("xyz", "").split()]  # type: ignore[union-attr]
        assert xyz == pytest.approx(jp.xyz, abs=1e-9)
        assert rpy == pytest.approx(jp.rpy, abs=1e-9)
        assert axis == pytest.approx(jp.axis, abs=0)
        assert (j.find("parent").get("link"), j.find("child").get("link")) == (jp.parent, jp.child)  # type: ignore[union-attr]
