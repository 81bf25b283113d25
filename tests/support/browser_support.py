"""Helpers of the tests that look at a page as a person would: Debian's headless chromium, run without any network
(a new network namespace), or the test is skipped saying why."""

from __future__ import annotations

import shutil
import subprocess

import pytest


def offline_prefix() -> list[str]:
    """A command prefix that runs a program without any network (a new network namespace), or skip."""
    for prefix in (["unshare", "-n"], ["unshare", "-rn"]):
        if shutil.which(prefix[0]) and subprocess.run([*prefix, "true"], capture_output=True).returncode == 0:
            return prefix
    pytest.skip("cannot make a network namespace (unshare -n) to open the page offline")


def chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.skip("Debian's chromium is not installed (tools/ensure-system-deps.sh installs it)")
    return exe
