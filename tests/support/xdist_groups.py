"""A pytest hook (tests/conftest.py imports it): under ``--dist loadgroup`` (make test's wall-clock phase) the tests of
one module that share a module-scoped fixture go to one xdist worker, so that the fixture (a station, a built wheel,
a ROS 2 environment's graph) starts once.

Run alone: ``pytest -p tests.support.xdist_groups -n N --dist loadgroup ...`` (tests/test_xdist_groups.py does).
"""

from __future__ import annotations

import pytest

SHARED_SCOPES = ("module", "package", "class")


@pytest.hookimpl(tryfirst=True)  # before xdist reads the groups
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Under ``--dist loadgroup`` (make test's wall-clock phase) the tests of one module that share a module-scoped
    fixture (a station, a built wheel, a ROS 2 environment's graph) go to one worker, so that it starts once; one
    group per value of a parametrised one (Jazzy and Kilted may run side by side). Other tests go one by one."""
    for item in items:
        info = getattr(item, "_fixtureinfo", None)
        if info is None or item.get_closest_marker("xdist_group") is not None:
            continue
        shared = sorted(name for name, defs in info.name2fixturedefs.items() if defs[-1].scope in SHARED_SCOPES)
        if shared:
            params = getattr(getattr(item, "callspec", None), "params", {})
            values = [f"{name}={params[name]}" for name in shared if name in params]
            item.add_marker(pytest.mark.xdist_group("|".join([item.nodeid.split("::", 1)[0], *values])))
    if getattr(config.option, "loadgroup", False):  # set in the workers of --dist loadgroup
        _group_ids(items)


def _group_ids(items: list[pytest.Item]) -> None:
    """xdist's loadgroup sends the tests whose node id ends in ``@GROUP`` to one worker. xdist 3.8 writes that suffix
    into ``item._nodeid``, which pytest 9.2's structured node ids no longer read: grouping silently stops
    (https://github.com/pytest-dev/pytest-xdist/issues/1386). Until xdist writes it where pytest reads it (its pull
    request 1388 does what this does), the suffix goes into the structured id; on a pytest without one, xdist's own
    suffix works."""
    try:
        from _pytest.nodeid import NodeId
    except ImportError:
        return
    for item in items:
        groups = sorted({str(m.args[0] if m.args else m.kwargs.get("name", "default"))
                         for m in item.iter_markers("xdist_group")})
        if groups and isinstance(getattr(item, "_id", None), NodeId) and "@" not in item.nodeid:
            item._id = NodeId.parse(f"{item.nodeid}@{'_'.join(groups)}")
