"""tests/support/xdist_groups.py: under ``-n 2 --dist loadgroup`` a module-scoped fixture starts once per module (once
per value of a parametrised one), while the module's other tests still spread over the workers."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

from tests.support import REPO

MODULE = '''
import json, os, pathlib, time
import pytest

LOG = pathlib.Path(os.environ["SETUP_LOG"])


@pytest.fixture(scope="module", params=["jazzy", "kilted"])
def station(request):
    with LOG.open("a") as f:
        f.write(json.dumps(["station", request.param, os.environ["PYTEST_XDIST_WORKER"]]) + "\\n")
    return request.param


@pytest.mark.parametrize("i", range(4))
def test_uses_it(station, i):
    time.sleep(0.05)


@pytest.mark.parametrize("i", range(8))
def test_alone(i):
    with LOG.open("a") as f:
        f.write(json.dumps(["alone", i, os.environ["PYTEST_XDIST_WORKER"]]) + "\\n")
    time.sleep(0.05)
'''


def test_a_shared_module_fixture_starts_once_per_value_and_the_rest_spreads(tmp_path: Path) -> None:
    (tmp_path / "test_shared.py").write_text(MODULE)
    log = tmp_path / "setups.jsonl"
    env = dict(os.environ, SETUP_LOG=str(log), PYTHONPATH=str(REPO))
    result = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p",
                             "tests.support.xdist_groups", "-n", "2", "--dist", "loadgroup", "--rootdir",
                             str(tmp_path), "-c", os.devnull, str(tmp_path)], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    rows = [json.loads(line) for line in log.read_text().splitlines()]
    assert Counter(r[1] for r in rows if r[0] == "station") == {"jazzy": 1, "kilted": 1}, rows
    assert len({r[2] for r in rows if r[0] == "alone"}) == 2, rows  # ungrouped tests on both workers
