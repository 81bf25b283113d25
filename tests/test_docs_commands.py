"""Every command a page of the manual shows is run: each page's run blocks in order, in one shell, in a scratch
folder that stands for the root of a clone (links to the repository's .venv, ur3hanoi, docs and tests), and each
command must exit as the page says (docs/design.md, "Runnable blocks"). A page runs in the phase of its heaviest
block: ROS 1 pages with a private master in the wall-clock phase, ROS 2 pages inside a private network namespace.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.docs_support import REPO, PageError, doc_pages, page_name, page_phase, page_script, shell_blocks

TIMEOUT_S = 600.0
LINKED = (".venv", "ur3hanoi", "docs", "tests")


def _pages() -> list[object]:
    params = []
    for path in doc_pages():
        blocks = shell_blocks(path)
        if not any(b.run for b in blocks):
            continue
        phase = page_phase(blocks)
        marks = [] if phase == "cpu" else [getattr(pytest.mark, phase)]
        params.append(pytest.param(path, marks=marks, id=page_name(path)))
    return params


def _scratch(tmp_path: Path) -> Path:
    """A folder that stands for the root of a clone: the page's outputs go there, its inputs are links."""
    root = tmp_path / "clone"
    root.mkdir()
    for name in LINKED:
        (root / name).symlink_to(Path(sys.prefix) if name == ".venv" else REPO / name)
    return root


def _environment(phase: str, root: Path) -> dict[str, str]:
    env = dict(os.environ, PATH=f"{Path(sys.prefix) / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}",
               PYTHONUNBUFFERED="1")
    if phase == "ros":
        from tests.support.ros_support import free_port

        (root / "ros_home").mkdir()
        env.update(ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}", ROS_HOME=str(root / "ros_home"),
                   ROS_IP="127.0.0.1")
    if phase == "dds":
        env.update(ROS_DOMAIN_ID="0")
    return env


def _command(phase: str, script: str) -> list[str]:
    if phase == "ros":
        from tests.support.ros_support import ROS_INSTALLED

        if not ROS_INSTALLED and not os.environ.get("CI"):
            pytest.skip("ROS 1 not installed (run tools/ensure-system-deps.sh as root)")
    if phase == "dds":
        from tests.support.ros2_support import NETNS_PROBLEM

        if NETNS_PROBLEM is not None:
            pytest.skip(NETNS_PROBLEM)
        return ["unshare", "-n", "bash", "-c", "ip link set lo up && ip link set lo multicast on\n" + script]
    return ["bash", "-c", script]


@pytest.mark.parametrize("page", _pages())
def test_every_command_of_the_page_runs(page: Path, tmp_path: Path) -> None:
    blocks = shell_blocks(page)
    phase = page_phase(blocks)
    root = _scratch(tmp_path)
    proc = subprocess.Popen(_command(phase, page_script(blocks)), cwd=root, env=_environment(phase, root),
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        pytest.fail(f"{page_name(page)}: the page's commands did not finish within {TIMEOUT_S:.0f} s\n{err[-3000:]}")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    failed = [ln for ln in err.splitlines() if ln.startswith("DOCS-FAIL")]
    assert proc.returncode == 0 and out.rstrip().endswith("DOCS-OK"), (
        "\n".join(failed) or f"exit {proc.returncode}") + f"\n--- stderr (end) ---\n{err[-3000:]}"


def test_every_shell_block_is_marked() -> None:
    problems = []
    for path in doc_pages():
        try:
            shell_blocks(path)
        except PageError as exc:
            problems.append(str(exc))
    assert not problems, "\n".join(problems)


def test_an_unmarked_or_unreasoned_block_is_refused(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    for text, words in (("Run this:\n\n```bash\nur3hanoi --help\n```\n", "without a marker"),
                        ("<!-- shown -->\n```bash\nur3hanoi --help\n```\n", "needs a reason"),
                        ("<!-- run: fast -->\n```bash\nur3hanoi --help\n```\n", "unknown word 'fast'"),
                        ("<!-- run: background -->\n```bash\nur3hanoi a\nur3hanoi b\n```\n", "exactly one command")):
        page.write_text(text)
        with pytest.raises(PageError, match=words):
            shell_blocks(page)


def test_a_command_that_exits_otherwise_than_the_page_says_fails_the_page(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("<!-- run -->\n```bash\ntrue\nfalse\necho never\n```\n")
    proc = subprocess.run(["bash", "-c", page_script(shell_blocks(page))], cwd=tmp_path, capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 90 and "never" not in proc.stdout
    assert f"DOCS-FAIL {page_name(page)}:2: 'false' exited 1, the page expects 0" in proc.stderr
