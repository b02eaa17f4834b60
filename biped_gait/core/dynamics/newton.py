"""One solver for the project's square nonlinear systems F(x) = 0: damped Newton with an exact
Jacobian, and chord steps with a fixed Jacobian. The shooting BVP (``bvp``) and the walker's
per-step re-aim (``walk``) both use it.

A residual function returns F(x) and an auxiliary value (e.g. the flow that produced F, so that
the caller need not integrate again); Newton's also returns dF/dx when asked. Convergence is
tested on the max-norm of F against ``tol`` (in the units of F). Results are always returned;
``converged`` and ``status`` say whether to trust them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

CONVERGED = "converged"
DIVERGED = "diverged"  # a non-finite residual
SINGULAR = "singular"  # a singular Jacobian
EXHAUSTED = "exhausted"  # the iteration bound was reached
STALLED = "stalled"  # a chord step did not contract enough

NewtonResidual = Callable[[np.ndarray, bool], tuple[np.ndarray, "np.ndarray | None", Any]]
ChordResidual = Callable[[np.ndarray], tuple[np.ndarray, Any]]


@dataclass(frozen=True, eq=False)
class SolveResult:
    """The last accepted iterate ``x``, F(x), the auxiliary value of F at x, the Jacobian last
    used, the number of accepted steps, and the outcome (``status`` and a one-line ``message``)."""

    x: np.ndarray
    residual: np.ndarray
    aux: Any
    jacobian: np.ndarray | None
    iterations: int
    status: str
    message: str

    @property
    def converged(self) -> bool:
        return self.status == CONVERGED

    @property
    def norm(self) -> float:
        """Max-norm of the residual (inf if it is not finite)."""
        return max_norm(self.residual)


def max_norm(f: np.ndarray) -> float:
    """max |f_i|, or inf if an entry is not finite."""
    return float(np.max(np.abs(f))) if np.all(np.isfinite(f)) else math.inf


def newton(fun: NewtonResidual, x0: np.ndarray, tol: float, max_iter: int) -> SolveResult:
    """Damped Newton from ``x0``: ``fun(x, True)`` gives (F, dF/dx, aux), ``fun(x, False)`` (F,
    None, aux). Each step backtracks (halving, down to 1e-3) until the max-norm of F decreases by
    the Armijo factor (1 - 1e-4 lambda). The full step's Jacobian is evaluated with it, unless
    quadratic convergence predicts that step is the last one (10 |F|^2 < tol)."""
    x = np.asarray(x0, float)
    f, jac, aux = fun(x, True)
    norm = max_norm(f)
    for iteration in range(max_iter + 1):
        if not math.isfinite(norm):
            return SolveResult(x, f, aux, jac, iteration, DIVERGED, "non-finite residual")
        if norm < tol:
            return SolveResult(x, f, aux, jac, iteration, CONVERGED, CONVERGED)
        if iteration == max_iter:
            break
        try:
            step = np.linalg.solve(jac, -f)
        except np.linalg.LinAlgError:
            return SolveResult(x, f, aux, jac, iteration, SINGULAR, "singular Jacobian")
        lam = 1.0
        last_expected = 10.0 * norm * norm < tol
        while True:
            trial = x + lam * step
            f_new, jac_new, aux_new = fun(trial, lam == 1.0 and not last_expected)
            new_norm = max_norm(f_new)
            if new_norm < (1 - 1e-4 * lam) * norm or lam < 1e-3:
                break
            lam *= 0.5
        x, f, aux, norm = trial, f_new, aux_new, new_norm
        if math.isfinite(norm) and norm >= tol:
            jac = jac_new if jac_new is not None else fun(x, True)[1]
    return SolveResult(x, f, aux, jac, max_iter, EXHAUSTED, f"no convergence in {max_iter} Newton iterations")


def chord(
    fun: ChordResidual, x0: np.ndarray, jacobian: np.ndarray, tol: float, max_steps: int,
    contraction: float | None = None, start: tuple[np.ndarray, Any] | None = None,
) -> SolveResult:
    """Chord steps x <- x - J^-1 F(x) with the fixed ``jacobian`` from ``x0``; ``fun(x)`` gives
    (F, aux), ``start`` (F, aux) at ``x0`` if known. With ``contraction``, a step must shrink the
    max-norm of F by that factor or the iteration stops (``STALLED``) at the last accepted iterate."""
    x = np.asarray(x0, float)
    f, aux = fun(x) if start is None else start
    norm = max_norm(f)
    steps = 0
    while True:
        if not math.isfinite(norm):
            return SolveResult(x, f, aux, jacobian, steps, DIVERGED, "non-finite residual")
        if norm < tol:
            return SolveResult(x, f, aux, jacobian, steps, CONVERGED, CONVERGED)
        if steps == max_steps:
            return SolveResult(x, f, aux, jacobian, steps, EXHAUSTED, f"no convergence in {max_steps} chord steps")
        trial = x - np.linalg.solve(jacobian, f)
        f_new, aux_new = fun(trial)
        new_norm = max_norm(f_new)
        if contraction is not None and not new_norm < contraction * norm:
            return SolveResult(x, f, aux, jacobian, steps, STALLED, "chord steps stalled")
        x, f, aux, norm = trial, f_new, aux_new, new_norm
        steps += 1
