"""Pictures for people: the audit of a lab table (:mod:`~ur3hanoi.plots.audit`, ``check-table --plot``) and a
plan's joint motion against its limits (:mod:`~ur3hanoi.plots.plan`, ``plan --plot``), drawn with matplotlib (the
optional extra ``plot``: ``pip install 'ur3hanoi[plot]'``) and written atomically as PNG, SVG or PDF by the
extension.
"""

from __future__ import annotations

from ur3hanoi.plots.figure import PLOT_FORMATS, check_plot_path, require_matplotlib, save_figure

__all__ = ["PLOT_FORMATS", "check_plot_path", "require_matplotlib", "save_figure"]
