"""The command line starts without the heavy libraries: building the parser and every ``--help`` load none of them.

A property, not a timing (timings are in bench/bench_startup.py): which modules a fresh interpreter holds after
``import ur3hanoi.cli`` and after each command's ``--help``.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from tests.conftest import REPO
from ur3hanoi.cli import build_parser
from ur3hanoi.cli.common import SUCTION_PROFILES
from ur3hanoi.cli.options import TABLE_KEYS

HEAVY = ("numpy", "pinocchio", "coal", "hppfcl", "mujoco", "placo", "ruckig", "scipy", "yaml")
"""Libraries the parser must not import: each costs 10-150 ms; the commands import them where they are used."""
HELP_UNUSED = (*HEAVY, "dataclasses", "inspect")
"""What ``--help`` must not import either: :mod:`dataclasses` (with :mod:`inspect`, ``ast``, ``dis``) costs 8-10 ms,
a sixth of a ``--help``; the option ranges are NamedTuples (:class:`ur3hanoi.io.number.Number`)."""

_PROBE = """
import contextlib, io, json, sys
import ur3hanoi.cli
heavy = {heavy!r}
def loaded():
    return sorted(m for m in sys.modules if m.split(".")[0] in heavy)
out = {{"import": loaded()}}
for argv in {argvs!r}:
    with contextlib.redirect_stdout(io.StringIO()) as text:
        code = ur3hanoi.cli.main([*argv, "--help"])
    out[" ".join(argv) or "ur3hanoi"] = [code, len(text.getvalue()), loaded()]
print(json.dumps(out))
"""


def _commands() -> list[list[str]]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return [[], *([name] for name in sub.choices)]  # type: ignore[attr-defined]


def _probe(code: str) -> dict[str, object]:
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)  # type: ignore[no-any-return]


def test_parser_and_every_help_import_no_heavy_library() -> None:
    commands = _commands()
    assert len(commands) >= 7  # ur3hanoi itself and its commands (tables, check-table, ..., ros-env)
    out = _probe(_PROBE.format(heavy=HELP_UNUSED, argvs=commands))
    assert out.pop("import") == []
    assert set(out) == {" ".join(c) or "ur3hanoi" for c in commands}
    for name, (code, n_chars, loaded) in out.items():  # type: ignore[misc]
        assert code == 0 and n_chars > 200, f"{name} --help: exit {code}, {n_chars} characters"
        assert loaded == [], f"{name} --help imported {loaded}"


def test_the_probe_sees_a_heavy_import() -> None:
    """The check can fail: the same probe after a library import reports it."""
    out = _probe("import numpy\n" + _PROBE.format(heavy=HELP_UNUSED, argvs=[["tables"]]))
    assert "numpy" in out["import"]  # type: ignore[operator]
    out = _probe(_PROBE.format(heavy=HELP_UNUSED, argvs=[["tables"]]).replace("import ur3hanoi.cli\n",
                                                                               "import ur3hanoi.cli, dataclasses\n"))
    assert "dataclasses" in out["import"]  # type: ignore[operator]


def test_parser_constants_are_the_library_constants() -> None:
    """The parser spells out what it would otherwise import from numpy-heavy modules: the same values."""
    from ur3hanoi.io.limits import MAX_HEIGHTS, MAX_TOWERS
    from ur3hanoi.station.calibration import MAX_HEIGHTS as STATION_MAX_HEIGHTS
    from ur3hanoi.station.calibration import MAX_TOWERS as STATION_MAX_TOWERS
    from ur3hanoi.station.suction_profile import PROFILES
    from ur3hanoi.tables import TABLE_KEYS as LAB_TABLE_KEYS

    assert TABLE_KEYS == LAB_TABLE_KEYS
    assert tuple(PROFILES) == SUCTION_PROFILES
    assert (MAX_TOWERS, MAX_HEIGHTS) == (STATION_MAX_TOWERS, STATION_MAX_HEIGHTS)


def test_python_m_ur3hanoi_is_the_command() -> None:
    """``python -m ur3hanoi`` (what bench scripts use, no ``ur3hanoi`` on PATH needed) runs the same parser."""
    proc = subprocess.run([sys.executable, "-m", "ur3hanoi", "plan", "--blocks", "0"], capture_output=True,
                          text=True, cwd=REPO, timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.startswith("ur3hanoi: error: argument --blocks:"), proc.stderr
    assert "ur3hanoi plan --help" in proc.stderr


_RUN_PROBE = """
import contextlib, io, json, sys
import ur3hanoi.cli
with contextlib.redirect_stdout(io.StringIO()):
    code = ur3hanoi.cli.main({argv!r})
print(json.dumps([code, sorted(m for m in sys.modules if m.split(".")[0] in {heavy!r})]))
"""


_TABLES_PROBE = """
import contextlib, io, json, sys
import ur3hanoi.cli
with contextlib.redirect_stdout(io.StringIO()):
    code = ur3hanoi.cli.main({argv!r})
print(json.dumps([code, sorted(m for m in sys.modules if m.split(".")[0] in {heavy!r}
                               or m in ("ur3hanoi.robot.ik", "ur3hanoi.tables.ik_table",
                                        "ur3hanoi.station.calibration"))]))
"""


def test_tables_needs_no_pinocchio(tmp_path: Path) -> None:
    """The closed form solves every pose of a shipped station within 1e-9 m / rad, measured by the NumPy FK of the
    URDF chain: ``tables`` imports neither Pinocchio (nor coal, placo) nor anything else heavy but NumPy and YAML,
    first run or rerun on its own output."""
    for station, key in (("lab_sim", "sim_pos"), ("lab_real", "real_pos")):
        argv = ["tables", station, "--key", key, "-o", str(tmp_path / f"{station}.yaml")]
        for _ in range(2):
            proc = subprocess.run([sys.executable, "-c", _TABLES_PROBE.format(argv=argv, heavy=HELP_UNUSED)],
                                  capture_output=True, text=True, cwd=REPO, timeout=120)
            assert proc.returncode == 0, proc.stderr
            code, loaded = json.loads(proc.stdout)
            assert code == 0
            assert {m.split(".")[0] for m in loaded} == {"numpy", "yaml", "ur3hanoi", "dataclasses", "inspect"}, loaded
            assert {"ur3hanoi.robot.ik", "ur3hanoi.tables.ik_table", "ur3hanoi.station.calibration"} <= set(loaded)


def test_a_plan_from_the_user_cache_needs_no_pinocchio_coal_or_scipy(tmp_path: Path) -> None:
    """The second ``plan`` of a station reads its connections, waypoints and clearance result from the user's cache:
    it imports neither Pinocchio nor coal (the clearance check) nor SciPy (the search), nor MuJoCo or placo."""
    import os

    argv = ["plan", "--start", "1", "--end", "3", "--calibration", "lab_sim"]
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "xdg")}
    runs = []
    for _ in range(2):
        proc = subprocess.run([sys.executable, "-c", _RUN_PROBE.format(argv=argv, heavy=HEAVY)], capture_output=True,
                              text=True, cwd=REPO, timeout=300, env=env)
        assert proc.returncode == 0, proc.stderr
        runs.append(json.loads(proc.stdout))
    (code_first, first), (code, loaded) = runs
    assert code_first == code == 0
    assert {"pinocchio", "coal"} <= {m.split(".")[0] for m in first}  # the first run checks the clearances
    assert {m.split(".")[0] for m in loaded} == {"numpy", "yaml", "ruckig"}, loaded


def _subparsers(parser: object) -> dict[str, object]:
    return next(a for a in parser._actions if a.dest == "command").choices  # type: ignore[attr-defined, no-any-return]


def test_a_command_builds_only_its_own_parser(monkeypatch: object) -> None:
    """Every command is in :data:`COMMAND_MODULES`, its own parser is the full parser's to the letter, and a run
    imports no other command's module."""
    from ur3hanoi.cli.main import COMMAND_MODULES

    monkeypatch.setenv("COLUMNS", "100")  # type: ignore[attr-defined]
    full = _subparsers(build_parser())
    assert list(COMMAND_MODULES) == list(full)
    for name in COMMAND_MODULES:
        own = _subparsers(build_parser(name))
        assert name in own and len(own) < len(full)
        assert own[name].format_help() == full[name].format_help()  # type: ignore[attr-defined]
    probe = ("import sys, contextlib, io, json\nimport ur3hanoi.cli\n"
             "with contextlib.redirect_stdout(io.StringIO()):\n    ur3hanoi.cli.main(['tables', '--help'])\n"
             "print(json.dumps(sorted(m for m in sys.modules if m.startswith('ur3hanoi.cli.'))))")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, cwd=REPO, timeout=60)
    assert proc.returncode == 0, proc.stderr
    loaded = {m.removeprefix("ur3hanoi.cli.") for m in json.loads(proc.stdout)}
    others = set(COMMAND_MODULES.values()) - {"tables"}
    assert loaded & others == set(), f"tables imported {sorted(loaded & others)}"
