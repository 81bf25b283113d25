"""Connections kept in the user's cache (:mod:`ur3hanoi.io.cache`), so a new process plans without searching again.

A connection's search (the via cells, the interior points of its legs, the blends: SciPy's Nelder-Mead over many
Ruckig calculations, and the 1 kHz corridor checks) is most of a cold plan; its result is a function of the station
geometry, the robot model and the planning settings alone. :func:`connect` keeps it on disk:

- **What is kept**: the joint states [rad, rad/s, rad/s^2] of the exit leg, of the motion across and of the entry
  leg, each leg's checked deviation [m] and the via cells, as JSON (floats written by ``repr``: they read back bit for
  bit). The Ruckig trajectories are recalculated from the states (one calculation per segment, deterministic: the
  same trajectories as the search produced, since every segment of a connection is one Ruckig calculation between
  two consecutive states). A connection with an exact path-following leg (a 1-DoF trajectory) is not kept.
- **Key**: :func:`~ur3hanoi.plan.cache_key.station_inputs` (station geometry, robot model, Ruckig and NumPy
  versions, the planner's source), the planning limits, corridor, via grid, pass-through and blend settings, and
  the connection (slots and over heights): a changed input or a changed planner is a new entry, never a stale plan.
- An entry that does not decode, or whose states Ruckig no longer connects, is rebuilt
  (:func:`ur3hanoi.io.cache.cached`).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from ur3hanoi.io.cache import cached
from ur3hanoi.plan.cache_key import station_inputs
from ur3hanoi.plan.motion.corridor import Leg, State
from ur3hanoi.plan.motion.waypoints import geometry_key
from ur3hanoi.plan.route.connections import Connection, ConnectionKey, Slot, StationPlanner

CONNECTION = "plan-connection"
"""Kind of the cache entries of :func:`connect`."""


def connect(planner: StationPlanner, slot0: Slot | None, slot1: Slot | None, over0: float | None = None,
            over1: float | None = None) -> Connection:
    """:meth:`StationPlanner.connect`, through the user's cache: the same connection, bit for bit."""
    key: ConnectionKey = (slot0, slot1, over0, over1)
    found = planner.memoized(key)
    if found is None:
        inputs = [*_planner_inputs(planner), repr(key).encode()]
        found = cached(CONNECTION, inputs, lambda: planner.connect(*key), _encode,
                       lambda payload: _decode(payload, planner))
        planner.memoize(key, found)
    return found


@lru_cache(maxsize=8)
def _planner_inputs(planner: StationPlanner) -> tuple[bytes, ...]:
    lim = planner.limits
    settings = (lim.v_max.tolist(), lim.a_max.tolist(), lim.j_max.tolist(), planner.tol_m, planner.via_speeds,
                planner.via_accels, planner.blend)
    return (*station_inputs(geometry_key(planner.station)), repr(settings).encode())


def _encode_states(states: Sequence[State]) -> list[list[list[float]]]:
    return [[np.asarray(x, dtype=float).tolist() for x in s] for s in states]


def _encode_leg(leg: Leg | None) -> dict[str, object] | None:
    return None if leg is None else {"states": _encode_states(leg.states), "deviation_m": leg.deviation_m}


def _encode(c: Connection) -> bytes | None:
    if any(leg is not None and leg.path is not None for leg in (c.exit, c.entry)):
        return None  # an exact path-following leg: its 1-DoF trajectory is not a chain of joint states
    doc = {"exit": _encode_leg(c.exit), "across": _encode_states(c.across_states), "entry": _encode_leg(c.entry),
           "cells": [list(cell) if cell is not None else None for cell in c.cells]}
    return json.dumps(doc).encode()


def _decode_states(doc: object) -> tuple[State, ...]:
    if not isinstance(doc, list) or len(doc) < 2:
        raise ValueError("a chain needs two states or more")
    states = []
    for s in doc:
        q, v, a = (np.array(x, dtype=np.float64) for x in s)
        if q.ndim != 1 or q.size == 0 or not q.shape == v.shape == a.shape:
            raise ValueError("malformed joint state")
        states.append((q, v, a))
    return tuple(states)


def _decode(payload: bytes, planner: StationPlanner) -> Connection | None:
    doc = json.loads(payload)
    legs: list[Leg | None] = []
    for name in ("exit", "entry"):
        item = doc[name]
        if item is None:
            legs.append(None)
            continue
        states = _decode_states(item["states"])
        chain = planner.ruckig.chain(states)
        if chain is None:
            return None
        legs.append(Leg(states, tuple(chain), sum(t.duration for t in chain), float(item["deviation_m"])))
    across_states = _decode_states(doc["across"])
    across = planner.ruckig.chain(across_states)
    if across is None:
        return None
    c0, c1 = (tuple(int(i) for i in cell) if cell is not None else None for cell in doc["cells"])
    if len(c0 or (0, 0)) != 2 or len(c1 or (0, 0)) != 2:
        raise ValueError("malformed via cell")
    return Connection(legs[0], across_states, tuple(across), legs[1], (c0, c1))  # type: ignore[arg-type]
