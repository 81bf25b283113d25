"""ur3hanoi.robot.registry: every description is usable, the UR3's and UR3e's numbers are UR's published ones and
are written nowhere else in the source, and the UR URDF layout built from a DH table reproduces example-robot-data's
UR3 URDF (an independent file)."""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path
from xml.etree import ElementTree

import pytest

from tests.support import REPO
from ur3hanoi.robot.model import JointLimits
from ur3hanoi.robot.registry import ROBOTS, UR3, UR3E, DHParameters, check_description, robot_description
from ur3hanoi.robot.urdf import ur_layout, urdf_path


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


def test_ur3_dh_is_urs_published_table() -> None:
    """Universal Robots' DH table of the UR3 (CB3): d1 = 0.1519, a2 = -0.24365, a3 = -0.21325, d4 = 0.11235,
    d5 = 0.08535, d6 = 0.0819 m; the UR twists."""
    assert UR3.dh.d == (0.1519, 0.0, 0.0, 0.11235, 0.08535, 0.0819)
    assert UR3.dh.a == (0.0, -0.24365, -0.21325, 0.0, 0.0, 0.0)
    assert UR3.dh.alpha == pytest.approx((math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0), abs=0.0)
    assert JointLimits.for_robot(UR3) == JointLimits.ur3()


# UR's published link lengths [m] (d1, a2, a3, d4, d5, d6; a2, a3 negative in the tables), written here
# independently of the registry, and the same in millimetres.
LINK_LENGTHS_M = {"ur3": ("0.1519", "0.24365", "0.21325", "0.11235", "0.08535", "0.0819"),
                  "ur3e": ("0.15185", "0.24355", "0.2132", "0.13105", "0.08535", "0.0921")}
LINK_LENGTHS_MM = {"ur3": ("151.9", "243.65", "213.25", "112.35", "85.35", "81.9"),
                   "ur3e": ("151.85", "243.55", "213.2", "131.05", "85.35", "92.1")}


def _pattern(x: str) -> str:
    """``x`` as a whole number (not a part of 10.1519 or 0.15190), also written without its leading zero."""
    body = "0?" + re.escape(x[1:]) if x.startswith("0.") else re.escape(x)
    return rf"(?<![\d.]){body}(?!\d)"


_NUMBER = re.compile("|".join(_pattern(x) for table in (LINK_LENGTHS_M, LINK_LENGTHS_MM)
                              for lengths in table.values() for x in lengths))
SCANNED = ("ur3hanoi", "bench", "tools", "notebooks", "docs")
"""The source folders the lengths must not be copied into (the README is prose for people, tests/ states them
independently on purpose)."""
GENERATED = re.compile(r"ur3hanoi/robot/models/[^/]+/[^/]+\.xml$|^bench/REPORT\.md$")
"""MuJoCo robot files derived from the URDF or the registry (written by ur3hanoi.sim; tests/sim check they are
current): their numbers are computed from the one home, not copied by hand; and the benchmark report, whose
measured figures may equal a link length by chance (92.1 ms once)."""


def link_length_copies(root: Path, folders: tuple[str, ...] = SCANNED) -> list[str]:
    """``path:line: number`` of every UR3 or UR3e link length (with or without sign, in m or mm) written in a text
    file under ``root``'s ``folders``, outside ``ur3hanoi/robot/registry.py`` and the generated model files."""
    out = []
    for folder in folders:
        for path in sorted((root / folder).rglob("*")):
            rel = path.relative_to(root).as_posix()
            if not path.is_file() or rel == "ur3hanoi/robot/registry.py" or GENERATED.search(rel) \
                    or "__pycache__" in rel:
                continue
            try:
                text = path.read_text(encoding="utf-8")
            except UnicodeDecodeError:
                continue  # meshes, pictures
            for n, line in enumerate(text.splitlines(), start=1):
                out += [f"{rel}:{n}: {m.group(0)}" for m in _NUMBER.finditer(line)]
    return out


def test_the_link_lengths_are_written_once_in_the_source() -> None:
    assert link_length_copies(REPO) == []
    # The registry itself holds them (the scan would see a copy).
    registry = (REPO / "ur3hanoi/robot/registry.py").read_text(encoding="utf-8")
    assert {m.group(0) for m in _NUMBER.finditer(registry)} == {
        x for lengths in LINK_LENGTHS_M.values() for x in lengths}


@pytest.mark.parametrize("line", ["D1 = 0.1519  # UR3", "a = (0.0, -0.24365, -0.21325)", "d6 = .0921 m",
                                  "the UR3e's forearm (213.2 mm)"])
def test_a_planted_copy_is_found(tmp_path: Path, line: str) -> None:
    (tmp_path / "ur3hanoi" / "robot").mkdir(parents=True)
    (tmp_path / "ur3hanoi" / "robot" / "registry.py").write_text(line + "\n")  # the home: allowed
    (tmp_path / "ur3hanoi" / "robot" / "model.py").write_text(f'"""{line}"""\n')
    (tmp_path / "ur3hanoi" / "models.xml").write_text("0.2\n0.15190\n10.1519\n0.08536\n")  # near misses
    found = link_length_copies(tmp_path, ("ur3hanoi",))
    assert found and all(f.startswith("ur3hanoi/robot/model.py:1: ") for f in found), found


def test_ur_layout_of_the_ur3_table_is_example_robot_datas_urdf() -> None:
    root = ElementTree.parse(urdf_path()).getroot()
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
