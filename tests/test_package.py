"""The package's own API (``from ur3hanoi import ...``): every name resolves to its home module's object, and
``import ur3hanoi`` imports none of them (every command imports the package)."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pytest

import ur3hanoi


@pytest.mark.parametrize("name", sorted(ur3hanoi.__all__))
def test_each_name_is_its_home_modules_object(name: str) -> None:
    home = importlib.import_module(f"ur3hanoi.{ur3hanoi._HOME[name]}")
    assert getattr(ur3hanoi, name) is getattr(home, name)


def test_all_lists_exactly_the_names_with_a_home() -> None:
    assert sorted(ur3hanoi.__all__) == sorted(ur3hanoi._HOME)


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'lod_station'"):
        ur3hanoi.lod_station  # noqa: B018


def test_importing_the_package_imports_nothing_else_of_it() -> None:
    probe = "import json, sys, ur3hanoi; print(json.dumps(sorted(m for m in sys.modules if m.startswith('ur3hanoi'))))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    assert json.loads(out) == ["ur3hanoi"]
