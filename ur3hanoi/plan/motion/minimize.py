"""Few-parameter minimisation for the planner's searches: SciPy's Nelder-Mead, stopped at a known lower bound.

Used for the interior via states of the approach legs (:mod:`ur3hanoi.plan.motion.legs`) and the blends
(:mod:`ur3hanoi.plan.motion.blend`): 2 to 4 parameters, a cost that is one or a few Ruckig calculations (``inf``
where infeasible), and a lower bound at which the optimum is reached. SciPy is imported on the first call only:
it takes about a second to import, and a plan whose legs are cached never searches.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

# Cost handed to SciPy for an infeasible point (inf would make its simplex arithmetic produce NaN).
_INFEASIBLE = 1e300


@dataclass(frozen=True)
class Minimum:
    """Result of :func:`nelder_mead`: the best point, its cost and the number of cost evaluations."""

    x: tuple[float, ...]
    fun: float
    evaluations: int


class _TargetReachedError(Exception):
    """Raised inside the cost to stop SciPy as soon as the lower bound is reached."""


def nelder_mead(f: Callable[[Sequence[float]], float], x0: Sequence[float], step: Sequence[float], *,
                max_evals: int = 200, f_target: float = -math.inf, x_tol: float = 1e-9, f_tol: float = 0.0) -> Minimum:
    """Minimise ``f`` from ``x0`` (``scipy.optimize.minimize``, method Nelder-Mead) with the initial simplex
    ``x0 + step[i] e_i``.

    Stops after ``max_evals`` evaluations, as soon as a cost is at most ``f_target`` (a known lower bound), or when
    the simplex is within ``x_tol`` and its costs within ``f_tol`` (SciPy's ``xatol``/``fatol``). ``f`` may return
    ``inf`` for infeasible points. Deterministic: same inputs, same result. Returns the best point evaluated.
    """
    from scipy.optimize import minimize

    x_start = np.asarray(x0, dtype=float)
    simplex = np.vstack([x_start, x_start + np.diag(np.asarray(step, dtype=float))])
    best: list[float | tuple[float, ...]] = [math.inf, tuple(float(v) for v in x_start)]
    evals = [0]

    def cost(x: np.ndarray) -> float:
        xt = tuple(float(v) for v in x)
        value = float(f(xt))
        evals[0] += 1
        if value < best[0]:  # type: ignore[operator]
            best[0], best[1] = value, xt
        if value <= f_target:
            raise _TargetReachedError
        return value if math.isfinite(value) else _INFEASIBLE

    with contextlib.suppress(_TargetReachedError):
        minimize(cost, x_start, method="Nelder-Mead",
                 options={"initial_simplex": simplex, "maxfev": max_evals, "xatol": x_tol, "fatol": f_tol})
    fun, x = best
    assert isinstance(fun, float) and isinstance(x, tuple)
    return Minimum(x, fun, evals[0])
