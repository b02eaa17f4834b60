"""The results page's section on the 13-DOF biped (``aoustin2013-hips``, a yaw, a roll and a pitch
joint in each hip) beside the paper's 9-DOF one: the optimal arm swing and its effort at the
paper's three points, the anti-normal gait at the same amplitude, the yaw momentum's jump, the
open-loop stability, and how the gait itself changes (knees, hips, clearance). L in m, T in s,
angles in rad inside, degrees on the page; W in N m s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from concurrent.futures import Executor

import numpy as np

from ..core.gait.gait import Gait
from ..core.model.params import load_params
from .study import FIG4_CASES, Study, run_study

HIPS_PARAMS = "aoustin2013-hips"


def hips_study(executor: Executor, coarse_step: float) -> Study:
    """The Fig. 4 sweep and the mode comparisons at the paper's three points for the hips set."""
    return run_study(executor, [load_params(HIPS_PARAMS)], FIG4_CASES, coarse_step=coarse_step)[0]


def _shape(gait: Gait) -> tuple[float, float, float, float]:
    """max |swing knee|, max |swing hip roll|, max |swing hip yaw| (deg) over the step, clearance (mm)."""
    q = gait.figures.samples.q
    names = gait.names.joints
    column = lambda name: q[:, names.index(name)] if name in names else np.zeros(len(q))  # noqa: E731
    return (math.degrees(np.abs(column("swing_knee")).max()), math.degrees(np.abs(column("swing_hip_roll")).max()),
            math.degrees(np.abs(column("swing_hip_yaw")).max()), 1e3 * gait.figures.min_swing_height)


def hips_lines(default: Study, hips: Study) -> list[str]:
    """The section: a table at the paper's three points, 9-DOF beside 13-DOF, and its reading."""
    lines = ["| L (m) | T (s) | alpha* 9 / 13 (deg) | W* 9 / 13 | W anti-normal at alpha* 9 / 13 | jump normal 9 / 13 | "
             "open-loop radius 9 / 13 | swing knee max 9 / 13 (deg) | swing hip roll, yaw max 13 (deg) | "
             "clearance 9 / 13 (mm) |", "|---:|---:|---|---|---|---|---|---|---|---|"]
    rows = []
    for case in FIG4_CASES:
        nine, thirteen = default.comparisons[case], hips.comparisons[case]
        g9, g13 = nine.optimum.gait, thirteen.optimum.gait
        k9, _, _, c9 = _shape(g9)
        k13, roll13, yaw13, c13 = _shape(g13)
        rows.append((case, nine, thirteen, g9, g13))
        lines.append(
            f"| {case[0]:.2f} | {case[1]:.2f} | {math.degrees(g9.arm_amplitude):.2f} / {math.degrees(g13.arm_amplitude):.2f} | "
            f"{g9.W:.3f} / {g13.W:.3f} | {nine.other.W:.3f} / {thirteen.other.W:.3f} | "
            f"{g9.double_support.yaw_momentum_jump:.3f} / {g13.double_support.yaw_momentum_jump:.3f} | {g9.stability.spectral_radius:.0f} / "
            f"{g13.stability.spectral_radius:.0f} | {k9:.1f} / {k13:.2f} | {roll13:.1f}, {yaw13:.1f} | "
            f"{c9:.1f} / {c13:.1f} |")
    lines.append("")
    lines += _reading(rows)
    return lines


def _reading(rows: Sequence[tuple]) -> list[str]:
    """What the hips' joints do, read off the table's rows."""
    w_ratio = [g13.W / g9.W for _, _, _, g9, g13 in rows]
    alpha_shift = [math.degrees(g13.arm_amplitude - g9.arm_amplitude) for _, _, _, g9, g13 in rows]
    anti_ratio9 = [n.other.W / g9.W for _, n, _, g9, _ in rows]
    anti_ratio13 = [t.other.W / g13.W for _, _, t, _, g13 in rows]
    interior = all(t.optimum.where == "interior minimum" for _, _, t, _, _ in rows)
    knee = max(_shape(g13)[0] for *_, g13 in rows)
    roll = max(_shape(g13)[1] for *_, g13 in rows)
    radius = [(g9.stability.spectral_radius, g13.stability.spectral_radius) for *_, g9, g13 in rows]
    return [
        f"- **The gait changes character**: with free hip joints (no torque in the single support, like every "
        f"joint) the ballistic swing leg no longer folds its knee to clear the ground; it swings out sideways "
        f"(hip roll up to {roll:.1f} deg) and back, with the knee straight to within {knee:.2f} deg. The 9-DOF "
        "gait's knee flexion continues into this one when the hips' lateral joints are released gradually (a "
        "continuation in an added rotor inertia on them, from locked to free: the knee's flexion shrinks to zero "
        "as its backward-bending twin does, and the two branches meet the straight-kneed gait).",
        f"- **Effort**: W* is {min(w_ratio):.2f} to {max(w_ratio):.2f} times the 9-DOF's at the paper's three "
        f"points; the optimal arm amplitude moves by {min(alpha_shift):+.1f} to {max(alpha_shift):+.1f} deg and "
        + ("is still an interior minimum." if interior else "is not an interior minimum at every point."),
        f"- **Anti-normal swing** costs {min(anti_ratio13):.3f} to {max(anti_ratio13):.3f} times the normal "
        f"swing at the same amplitude with the hips' joints (9-DOF: {min(anti_ratio9):.3f} to "
        f"{max(anti_ratio9):.3f}): the yaw the arms cancel is now partly taken by the hips' yaw joints.",
        f"- **Open-loop stability**: the spectral radius falls from {min(r[0] for r in radius):.0f} to "
        f"{max(r[0] for r in radius):.0f} (9-DOF) to {min(r[1] for r in radius):.0f} to "
        f"{max(r[1] for r in radius):.0f}: still unstable, the walker's re-aim is still needed, but an error "
        "grows several times less per step.",
    ]
