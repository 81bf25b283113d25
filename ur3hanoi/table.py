"""Transitional re-export: waypoint generation moved to :mod:`ur3hanoi.waypoints`, the lab file to
:mod:`ur3hanoi.labfile`. Kept only while ``ur3hanoi.plan`` and ``ur3hanoi.sim`` import ``generate_table`` from here;
new code imports from :mod:`ur3hanoi.waypoints`.
"""

from ur3hanoi.waypoints import Table, generate_table

__all__ = ["Table", "generate_table"]
