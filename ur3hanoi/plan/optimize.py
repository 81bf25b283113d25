"""A small deterministic Nelder-Mead minimiser for the few-parameter searches of the planner (no SciPy needed).

Used for the interior via states of the approach legs (:mod:`ur3hanoi.plan.legs`): 2 to 4 parameters, a cost
that is one or a few Ruckig calculations, and a known lower bound to stop at. Plain Python floats: the cost
functions are cheap (a few microseconds), so array overhead would dominate.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Minimum:
    """Result of :func:`nelder_mead`: the best point, its cost and the number of cost evaluations."""

    x: tuple[float, ...]
    fun: float
    evaluations: int


def nelder_mead(f: Callable[[Sequence[float]], float], x0: Sequence[float], step: Sequence[float], *,
                max_evals: int = 200, f_target: float = -math.inf, x_tol: float = 1e-9, f_tol: float = 0.0) -> Minimum:
    """Minimise ``f`` from ``x0`` with an initial simplex of ``x0 + step[i] e_i`` (standard coefficients 1, 2,
    1/2, 1/2).

    Stops after ``max_evals`` evaluations, when the best cost is at most ``f_target`` (a known lower bound: the
    optimum is reached), or when the simplex is smaller than ``x_tol`` in every coordinate and its costs differ
    by at most ``f_tol``. ``f`` may return ``inf`` for infeasible points. Deterministic: same inputs, same result.
    """
    n = len(x0)
    pts = [list(map(float, x0))]
    for i in range(n):
        p = list(pts[0])
        p[i] += float(step[i])
        pts.append(p)
    vals = [f(p) for p in pts]
    evals = n + 1

    def done() -> bool:
        best = min(vals)
        if best <= f_target or evals >= max_evals:
            return True
        spread = max(max(abs(p[i] - pts[0][i]) for p in pts) for i in range(n))
        return spread <= x_tol and max(vals) - best <= f_tol

    while not done():
        order = sorted(range(n + 1), key=lambda k: vals[k])
        pts, vals = [pts[k] for k in order], [vals[k] for k in order]
        c = [sum(p[i] for p in pts[:-1]) / n for i in range(n)]
        worst = pts[-1]
        xr = [2 * c[i] - worst[i] for i in range(n)]
        fr = f(xr)
        evals += 1
        if fr < vals[0]:
            xe = [3 * c[i] - 2 * worst[i] for i in range(n)]
            fe = f(xe)
            evals += 1
            pts[-1], vals[-1] = (xe, fe) if fe < fr else (xr, fr)
        elif fr < vals[-2]:
            pts[-1], vals[-1] = xr, fr
        else:
            xc = [0.5 * (c[i] + worst[i]) for i in range(n)]
            fc = f(xc)
            evals += 1
            if fc < vals[-1]:
                pts[-1], vals[-1] = xc, fc
            else:  # shrink towards the best point
                for k in range(1, n + 1):
                    pts[k] = [0.5 * (pts[0][i] + pts[k][i]) for i in range(n)]
                    vals[k] = f(pts[k])
                    evals += 1
    k = min(range(n + 1), key=lambda i: vals[i])
    return Minimum(tuple(pts[k]), vals[k], evals)
