"""``ur3hanoi teach --via ros2`` against the real Cyclone DDS ``ros2-station`` in a private network namespace (marked
``dds``, wall clock): the same practice session as over ROS 1 (tests/support/teach_operator.py drives teach's
pseudo-terminal inside the namespace), on the hidden station, then ``ros2-solve`` with the written table.

The station runs ``--timing honest`` (each command as the controller's movej at the message's v and a) so that the
jog steps take their second; the course bridge's fixed 2 s moves would only make the test slower.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.support.ros2_support import REPO, in_netns, requires_netns
from tests.support.teach_operator import ERRORS_MM, JOG_RESOLUTION_MM, write_hidden_station
from ur3hanoi.station.calibration import load_station

pytestmark = [pytest.mark.dds, requires_netns]


def test_a_practice_session_over_dds_teaches_the_hidden_station_and_ros2_solve_solves_on_it(tmp_path: Path) -> None:
    hidden = write_hidden_station(tmp_path / "hidden.yaml")
    script = f"""
$UR3HANOI ros2-station --calibration {tmp_path}/hidden.yaml --timing honest --report {tmp_path}/report.json \\
  > {tmp_path}/st.out 2> {tmp_path}/st.err &
ST=$!
wait_ready {tmp_path}/st.err || exit 90
{sys.executable} -m tests.support.teach_operator {tmp_path} ros2 > {tmp_path}/operator.json \\
  || {{ kill -INT $ST; exit 91; }}
$UR3HANOI ros2-solve --table {tmp_path}/lab2_data.yaml --key real_pos --calibration {tmp_path}/station.yaml \\
  --start 1 --end 3 --v 4 --a 4 --json
CODE=$?
kill -INT $ST; wait $ST; echo "station exit $?" >&2
exit $CODE
"""
    result = in_netns(script, 300.0, REPO)
    transcript = (tmp_path / "transcript.txt").read_text() if (tmp_path / "transcript.txt").exists() else ""
    assert result.returncode == 0, result.stdout + result.stderr + transcript + (tmp_path / "st.err").read_text()
    seen = json.loads((tmp_path / "operator.json").read_text())
    assert seen["exit"] == 0 and seen["moving_refused"]
    assert "tower 3 height 1 is 1" in seen["suspect"] and seen["suspect"].count("re-record it") == 1
    assert "tower 1 height 1 is " in seen["wrong_slot"] and "SUSPECT" in seen["wrong_slot"]
    assert "every point agrees with the others" in seen["after"]
    assert "ur3hanoi's simulated station, no pendant" in transcript and "ROS_DOMAIN_ID 0 (loopback)" in transcript
    assert "next, slowly" in transcript and "ur3hanoi ros2-solve --table" in transcript

    fitted = load_station(tmp_path / "station.yaml")
    error_mm = np.linalg.norm(np.subtract(fitted.tower_origins, hidden.tower_origins), axis=1) * 1e3
    bound = [float(np.linalg.norm(e)) + math.sqrt(3) * JOG_RESOLUTION_MM / 2 + 0.2 for e in ERRORS_MM]
    assert np.all(error_mm <= bound), (error_mm, bound)

    outcome = json.loads(result.stdout.strip().splitlines()[-1])
    assert outcome["status"] == "solved" and outcome["moves"] == 7
    assert "station exit 0" in result.stderr
    report = json.loads((tmp_path / "report.json").read_text())
    assert {(b["block"], b["tower"], b["height"]) for b in report["final"]["blocks"]} == {(1, 3, 1), (2, 3, 2),
                                                                                         (3, 3, 3)}
