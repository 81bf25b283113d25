"""The lab's waypoint table: generate ``Q[tower][height][k]`` by IK, read and write ``lab2_data.yaml``, check it.

File format (the course's): top-level keys ``sim_pos`` / ``real_pos``, each ``Q[tower][height][k]`` with six joint
angles [rad] (controller convention), ``k = 0`` the contact ("on") pose and ``k = 1`` the pose above it; plus
``block_xy_pos[tower][height] = [x, y]`` [m, world] for the flat simulator layout.

Writing replaces only the keys it generates: every other top-level key keeps its exact text, the write is atomic
(temporary file + rename) and the bytes are a pure function of the inputs.
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ur3hanoi import __version__
from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import TableError
from ur3hanoi.grid import POSE_NAMES, T_base_tcp, T_world_tcp, block_xy_pos
from ur3hanoi.ik import IKResult, IKSolver, branch_of, make_solver, pose_errors, solve_on_branch
from ur3hanoi.robot import N_JOINTS, load_ur3
from ur3hanoi.station import Station

TABLE_KEYS: tuple[str, ...] = ("sim_pos", "real_pos")
BLOCK_XY_KEY = "block_xy_pos"


@dataclass(frozen=True)
class Table:
    """A generated table. ``q[tower, height, k]`` are joint angles [rad]; ``results`` the per-pose IK outcomes."""

    station: Station
    q: FloatArray  # shape (n_towers, n_heights, 2, 6)
    results: tuple[IKResult, ...]
    solver: str

    @property
    def max_position_error(self) -> float:
        return max(r.position_error for r in self.results)

    @property
    def max_orientation_error(self) -> float:
        return max(r.orientation_error for r in self.results)


def pose_label(tower: int, height: int, k: int) -> str:
    return f"tower {tower} height {height} {POSE_NAMES[k]}"


def generate_table(station: Station, solver: str | IKSolver = "pinocchio") -> Table:
    """IK of every grid pose of ``station`` on the home branch (see :func:`ur3hanoi.ik.solve_on_branch`).

    Raises:
        IKError: a pose is unreachable or out of limits; the message names tower, height and on/above.
    """
    if isinstance(solver, str):
        solver = make_solver(solver, load_ur3(station.tool, station.limits))
    q = np.empty((station.n_towers, station.n_heights, 2, N_JOINTS))
    results = []
    home_branch = branch_of(station.q_home_array)
    for t in range(station.n_towers):
        for h in range(station.n_heights):
            for k in (0, 1):
                res = solve_on_branch(solver, T_base_tcp(station, t, h, k), station.q_home_array,
                                      label=f"{station.source}: {pose_label(t, h, k)}", home_branch=home_branch)
                q[t, h, k] = res.q
                results.append(res)
    return Table(station=station, q=q, results=tuple(results), solver=solver.name)


# ---------------------------------------------------------------------------------------------------- reading


def read_yaml_mapping(path: str | Path) -> dict[str, Any]:
    """Parse a lab-format YAML file into a mapping (raises TableError naming the file)."""
    p = Path(path)
    try:
        data = yaml.safe_load(p.read_text())
    except OSError as exc:
        raise TableError(f"{p}: cannot read table file ({exc.strerror})") from None
    except yaml.YAMLError as exc:
        raise TableError(f"{p}: not valid YAML ({str(exc).splitlines()[0]})") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise TableError(f"{p}: expected a YAML mapping with keys such as {TABLE_KEYS}, got {type(data).__name__}")
    return data


def parse_q(value: Any, where: str) -> FloatArray:
    """Validate ``Q[tower][height][k][6]`` and return it as an array of shape (T, H, 2, 6) [rad]."""
    if not isinstance(value, list) or not value:
        raise TableError(f"{where}: expected a list Q[tower][height][k] of 6 joint angles, got {value!r:.60}")
    n_h = None
    for t, tower in enumerate(value):
        if not isinstance(tower, list) or not tower:
            raise TableError(f"{where}[{t}]: expected a list of heights, got {tower!r:.60}")
        n_h = len(tower) if n_h is None else n_h
        if len(tower) != n_h:
            raise TableError(f"{where}[{t}]: has {len(tower)} heights, tower 0 has {n_h} (all towers alike)")
        for h, pair in enumerate(tower):
            if not isinstance(pair, list) or len(pair) != 2:
                raise TableError(f"{where}[{t}][{h}]: expected 2 poses [on, above], got {pair!r:.60}")
            for k, q in enumerate(pair):
                ok = isinstance(q, list) and len(q) == N_JOINTS and all(
                    isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) for x in q)
                if not ok:
                    raise TableError(f"{where}[{t}][{h}][{k}]: expected {N_JOINTS} finite joint angles [rad], "
                                     f"got {q!r:.80}")
    return np.array(value, dtype=float)


def read_table(path: str | Path, key: str) -> FloatArray:
    """``Q`` of ``key`` in a lab-format file as an array (T, H, 2, 6) [rad]."""
    data = read_yaml_mapping(path)
    if key not in data:
        raise TableError(f"{path}: key '{key}' not found (keys present: {sorted(data)})")
    return parse_q(data[key], f"{path}:{key}")


# ---------------------------------------------------------------------------------------------------- writing


def _num(x: float) -> str:
    return repr(float(x)) if x != 0.0 else "0.0"


def format_q(q: FloatArray, key: str) -> str:
    """Block-YAML text of ``key: Q[tower][height][k]`` with one commented 6-vector per line."""
    lines = [f"{key}:"]
    for t in range(q.shape[0]):
        for h in range(q.shape[1]):
            for k in (0, 1):
                prefix = ("- " if h == 0 and k == 0 else "  ") + ("- " if k == 0 else "  ") + "- "
                vec = ", ".join(_num(v) for v in q[t, h, k])
                lines.append(f"{prefix}[{vec}]  # {pose_label(t, h, k)}")
    return "\n".join(lines) + "\n"


def format_xy(xy: Sequence[Sequence[Sequence[float]]]) -> str:
    lines = [f"{BLOCK_XY_KEY}:"]
    for t, tower in enumerate(xy):
        for h, p in enumerate(tower):
            prefix = "- " if h == 0 else "  "
            # Rounded to 1e-10 m: exact enough, and reads 0.3 rather than 0.30000000000000004.
            x, y = (round(float(v), 10) for v in p[:2])
            lines.append(f"{prefix}- [{_num(x)}, {_num(y)}]  # tower {t} height {h} [m, world]")
    return "\n".join(lines) + "\n"


_TOP_KEY = re.compile(r"^([A-Za-z_][\w\-]*)\s*:")
_HEADER = re.compile(r"^# ur3hanoi .*?: (\S+) generated from ")


def _split_sections(text: str) -> tuple[list[str], list[tuple[str | None, str]]]:
    """Split a block-mapping YAML document into (leading comment lines, [(top-level key, text)...])."""
    lines = text.splitlines(keepends=True)
    header: list[str] = []
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        header.append(lines[i])
        i += 1
    sections: list[tuple[str | None, str]] = []
    for line in lines[i:]:
        m = _TOP_KEY.match(line)
        if m:
            sections.append((m.group(1), line))
        elif sections:
            k, body = sections[-1]
            sections[-1] = (k, body + line)
        else:
            sections.append((None, line))
    return header, sections


def splice_yaml(old_text: str, new_sections: Mapping[str, str], header_lines: Mapping[str, str]) -> str:
    """Replace (or append) the given top-level sections, keeping every other key's text byte for byte.

    ``header_lines`` maps a key to its provenance comment; provenance lines of other keys are kept if their key
    still exists.
    """
    header, sections = _split_sections(old_text)
    out_sections: list[str] = []
    seen: set[str] = set()
    for key, body in sections:
        if key in new_sections:
            out_sections.append(new_sections[key])
            seen.add(key)
        else:
            if body and not body.endswith("\n"):
                body += "\n"
            out_sections.append(body)
    for key, body in new_sections.items():
        if key not in seen:
            out_sections.append(body)
    present = {k for k, _ in sections if k} | set(new_sections)
    kept_header: dict[str, str] = {}
    other_header: list[str] = []
    for line in header:
        m = _HEADER.match(line)
        if m:
            if m.group(1) in present and m.group(1) not in header_lines:
                kept_header[m.group(1)] = line.rstrip("\n")
        elif line.strip() and not line.startswith("# Generated by ur3hanoi") and not line.startswith("# Q["):
            other_header.append(line.rstrip("\n"))
    kept_header.update(header_lines)
    head = [
        "# Generated by ur3hanoi: lab2_data.yaml waypoint table (course format).",
        "# Q[tower][height][k]: 6 joint angles [rad], controller/DH convention; k = 0 on (contact), k = 1 above.",
        *other_header,
        *(kept_header[k] for k in sorted(kept_header)),
    ]
    return "\n".join(head) + "\n" + "".join(out_sections)


def atomic_write(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` via a temporary file in the same directory and an atomic rename."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        if p.exists():
            os.chmod(tmp, p.stat().st_mode & 0o777)
        else:  # mkstemp creates 0600; a new file gets the usual permissions (0666 less the umask)
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, p)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_table(path: str | Path, table: Table, key: str, calibration_label: str | None = None) -> str:
    """Write ``table`` under ``key`` into ``path`` (created or updated in place; see the module docstring).

    Returns the text written. Raises TableError (file untouched) if the existing file cannot be updated safely.
    """
    if key not in TABLE_KEYS:
        raise TableError(f"table key {key!r} is invalid: expected one of {TABLE_KEYS}")
    p = Path(path)
    old_text = ""
    old_data: dict[str, Any] = {}
    if p.exists():
        old_data = read_yaml_mapping(p)
        old_text = p.read_text()
    st = table.station
    label = calibration_label or st.source
    sections = {key: format_q(table.q, key)}
    headers = {key: f"# ur3hanoi {__version__}: {key} generated from {label} (sha256 {st.sha256 or 'n/a'}, "
                    f"{table.solver} IK)"}
    if st.layout == "flat":
        sections[BLOCK_XY_KEY] = format_xy(block_xy_pos(st))
        headers[BLOCK_XY_KEY] = f"# ur3hanoi {__version__}: {BLOCK_XY_KEY} generated from {label} " \
                                f"(sha256 {st.sha256 or 'n/a'})"
    text = splice_yaml(old_text, sections, headers)
    # Refuse to write anything that does not read back exactly: other keys equal, ours as generated.
    try:
        new_data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise TableError(f"{p}: cannot update in place (unusual YAML layout: {exc}); file left unchanged") from None
    for k, v in old_data.items():
        if k not in sections and new_data.get(k) != v:
            raise TableError(f"{p}: key '{k}' would change when updating '{key}'; file left unchanged")
    if not np.array_equal(np.array(new_data[key], dtype=float), table.q):
        raise TableError(f"{p}: '{key}' does not read back exactly; file left unchanged")
    atomic_write(p, text)
    return text


# --------------------------------------------------------------------------------------------------- checking


@dataclass(frozen=True)
class CheckRow:
    """FK error of one table entry against the calibration's intended pose."""

    tower: int
    height: int
    k: int
    position_error_mm: float
    orientation_error_deg: float
    ok: bool


def check_table(q: FloatArray, station: Station, tol_mm: float = 1.0, tol_deg: float = 0.5,
                where: str = "table") -> list[CheckRow]:
    """FK of every entry of ``q`` (T, H, 2, 6) vs ``station``'s intended TCP poses, in mm and deg."""
    if q.shape[:2] != (station.n_towers, station.n_heights):
        raise TableError(
            f"{where}: table has {q.shape[0]} towers x {q.shape[1]} heights, calibration {station.source} "
            f"has {station.n_towers} x {station.n_heights}"
        )
    robot = load_ur3(station.tool, station.limits)
    T_wb = station.T_world_base
    rows = []
    for t in range(q.shape[0]):
        for h in range(q.shape[1]):
            for k in (0, 1):
                dp, dr = pose_errors(T_wb * robot.fk(q[t, h, k]), T_world_tcp(station, t, h, k))
                mm, deg = dp * 1e3, math.degrees(dr)
                rows.append(CheckRow(t, h, k, mm, deg, mm <= tol_mm and deg <= tol_deg))
    return rows


__all__ = [
    "BLOCK_XY_KEY",
    "TABLE_KEYS",
    "CheckRow",
    "Table",
    "atomic_write",
    "check_table",
    "format_q",
    "generate_table",
    "parse_q",
    "read_table",
    "read_yaml_mapping",
    "write_table",
]
