"""Stability of the paper's gaits (docs/results.md): the open-loop Floquet multipliers (the
impulses held fixed) at the paper's three points for both modes, the walker's closed loop
(impulses re-solved from the actual state, the next step re-aimed) there, and whether the
optimal arm swing also minimizes the open-loop spectral radius.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..core.gait.configurations import GaitMode
from ..core.gait.gait import Gait
from ..core.model.params import BipedParams
from ..core.gait.planner import GaitRequest
from ..core.gait.stability import Multipliers, closed_loop
from ..core.walking.orbit import PlannedOrbit
from ..core.walking.runner import Walker
from .executors import planner_for


@dataclass(frozen=True, eq=False)
class PointStability:
    """A gait at one (L, T, alpha, mode): its open-loop and closed-loop multipliers."""

    gait: Gait
    closed: Multipliers


def point_stability(params: BipedParams, step_length: float, period: float, alpha: float,
                    mode: GaitMode) -> PointStability:
    """Worker entry: the gait at (L m, T s, alpha rad, mode) and its walker's closed loop."""
    planner = planner_for(params)
    gait = planner.plan(GaitRequest(step_length, period, alpha, mode))
    orbit = PlannedOrbit.of(gait)

    def walker_at(q: np.ndarray, qd: np.ndarray) -> Walker:
        walker = Walker(planner.hybrid, orbit, rate=1.0)
        walker.state = replace(walker.state, q=q, qd=qd)
        return walker

    return PointStability(gait, closed_loop(walker_at, np.concatenate([gait.step.q0, gait.step.qd_a])))


def stability_lines(points: Sequence[PointStability], curves: Sequence[Gait]) -> list[str]:
    """The results page's table and reading: ``points`` at the paper's optima, ``curves`` the
    Fig. 4 sweep (both modes, alpha 0..45 deg)."""
    lines = ["| L (m) | T (s) | alpha (deg) | mode | open-loop spectral radius | leading multipliers |moduli| | "
             "closed-loop spectral radius |", "|---:|---:|---:|---|---:|---|---:|"]
    for p in points:
        g = p.gait
        leading = ", ".join(f"{abs(v):.3g}" for v in g.stability.values[:4])
        lines.append(f"| {g.step_length:.2f} | {g.period:.2f} | {math.degrees(g.arm_amplitude):.2f} | {g.mode.value} | "
                     f"{g.stability.spectral_radius:.1f} | {leading} | {p.closed.spectral_radius:.4f} |")
    lines.append("")
    normal = [p for p in points if p.gait.mode is GaitMode.NORMAL]
    anti = [p for p in points if p.gait.mode is GaitMode.ANTI_NORMAL]
    lines.append(
        "- **Open loop the ballistic gaits are violently unstable**: with the impulses of the plan held fixed, "
        f"a small error grows {min(p.gait.stability.spectral_radius for p in points):.0f} to "
        f"{max(p.gait.stability.spectral_radius for p in points):.0f} times per step (a complex pair of "
        "multipliers: the error also turns). Anti-normal swing is "
        + ("more" if np.mean([p.gait.stability.spectral_radius for p in anti]) >
           np.mean([p.gait.stability.spectral_radius for p in normal]) else "less")
        + " unstable than normal swing at the same alpha.")
    lines.append(
        f"- **The walker's closed loop is stable but slow**: spectral radius "
        f"{min(p.closed.spectral_radius for p in points):.4f} to {max(p.closed.spectral_radius for p in points):.4f}. "
        "Re-solving the impulses and re-aiming each step lands every touchdown on the planned configuration, "
        "but the angular momentum about the foot-to-foot line, which no impulse of the double support can change, "
        "returns to the plan's only through the step durations, by about 1 % a step.")
    for length in sorted({g.step_length for g in curves}):
        curve = sorted((g for g in curves if g.step_length == length and g.mode is GaitMode.NORMAL and g.stability),
                       key=lambda g: g.arm_amplitude)
        if not curve:
            continue
        steadiest = min(curve, key=lambda g: g.stability.spectral_radius)
        cheapest = min((g for g in curve if g.usable), key=lambda g: g.W, default=None)
        if cheapest is not None:
            lines.append(
                f"- L = {length:g} m, normal: the open-loop spectral radius is least at alpha = "
                f"{math.degrees(steadiest.arm_amplitude):.1f} deg ({steadiest.stability.spectral_radius:.1f}); the "
                f"effort at {math.degrees(cheapest.arm_amplitude):.1f} deg, where the radius is "
                f"{cheapest.stability.spectral_radius:.1f}: the optimal arm swing "
                + ("also stabilizes most." if abs(steadiest.arm_amplitude - cheapest.arm_amplitude) <= math.radians(3)
                   else "is not the steadiest one."))
    return lines
