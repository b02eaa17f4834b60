"""Natural-parameter continuation of the ballistic BVP along a straight path in (L, T, alpha):
from a solved gait to a target request, each step warm-started from the last, the step halved
where Newton fails or jumps to another branch. It follows the branch it starts on (the
human-like one, when started from the atlas or the human-like seed).

Steps solve only the shooting problem on the coarse grid (no impulses, no figures): the result
is a warm start (qd(0) rad/s, theta rad) for the full solve at the target.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .bvp import StepProblem, solve_bvp
from ..dynamics.flow import BallisticFlow
from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import Settings

MAX_STEP = 1.0  # grid spacings of the atlas (0.025 m, 0.025 s, 5 deg; 0.05 m of step width) per continuation step
MIN_STEP = 1.0 / 64.0  # below this the path is given up
BRANCH_JUMP = 2.0  # rad/s: a larger change of qd(0) in one step is a jump to another branch
STEP_ITERATIONS = 12  # Newton iterations of one step: from a close warm start it needs 2 to 8
EXTRA_ATTEMPTS = 24  # failed (halved) steps allowed on a path, beyond one per grid spacing
SPACING = np.array([0.025, 0.025, math.radians(5.0)])  # m, s, rad
WIDTH_SPACING = 0.05  # m of step width


def path_length(start: tuple[float, float, float], target: tuple[float, float, float],
                widths: tuple[float, float] | None = None) -> float:
    """Distance from ``start`` to ``target`` (L m, T s, alpha rad) in grid spacings; ``widths``:
    the step widths (m) at both ends, when they differ."""
    length = float(np.linalg.norm((np.asarray(target) - np.asarray(start)) / SPACING))
    return length if widths is None else math.hypot(length, (widths[1] - widths[0]) / WIDTH_SPACING)


def continue_to(hybrid: HybridStep, flow: BallisticFlow, settings: Settings, start: tuple[float, float, float],
                guess: tuple[np.ndarray, float], target: StepProblem) -> tuple[np.ndarray, float] | None:
    """A warm start of ``target`` (its L m, T s, alpha rad, mode and closure) reached from the
    gait ``guess`` = (qd(0), theta) at ``start`` (L m, T s, alpha rad); None if the path cannot be
    followed (a step below ``MIN_STEP`` fails, or the steps exceed their budget). ``flow`` is the
    grid the steps are solved on (the coarse one). The target's step width (m) is reached along
    the same path from the hips' spacing, where ``guess`` is (None: the hips' spacing throughout)."""
    step_width = target.step_width
    start_a = np.asarray(start, float)
    target_a = np.array([target.step_length, target.period, target.arm_amplitude], float)
    spacing = hybrid.bm.params.hip_spacing
    widths = None if step_width is None or step_width == spacing else (spacing, step_width)
    length = path_length(start, tuple(target_a), widths)
    if length == 0.0:
        return guess
    coarse = replace(settings, tolerance=max(settings.tolerance, settings.coarse_tolerance),
                     max_iterations=STEP_ITERATIONS)
    s, ds = 0.0, min(1.0, MAX_STEP / length)
    qd, theta = np.asarray(guess[0], float), float(guess[1])
    attempts = math.ceil(length / MAX_STEP) + EXTRA_ATTEMPTS
    while s < 1.0:
        attempts -= 1
        if attempts < 0:
            return None
        s_next = min(1.0, s + ds)
        L, T, alpha = start_a + s_next * (target_a - start_a)
        if not (0.0 < L < 2 * hybrid.bm.params.leg_length and T > 0 and 0 <= alpha < math.pi / 2):
            return None
        width = None if widths is None else spacing + s_next * (step_width - spacing)
        on_path = replace(target, step_length=float(L), period=float(T), arm_amplitude=float(alpha), step_width=width)
        step = solve_bvp(hybrid, flow, on_path, (qd, theta), coarse)
        if step.converged and np.max(np.abs(step.qd_a - qd)) <= BRANCH_JUMP:
            s, qd, theta = s_next, step.qd_a, step.theta
            ds = min(2.0 * ds, MAX_STEP / length)
        else:
            ds *= 0.5
            if ds * length < MIN_STEP:
                return None
    return qd, theta
