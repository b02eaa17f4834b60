"""The accuracy contract of a plan (docs/model.md section 4.11) and the estimate that checks it.

The contract: every figure a plan reports (``FIGURES``: its keys in the plan's JSON) lies within
``FIGURE_BOUND`` of its converged value, the value a grid fine enough not to move it gives,
relative to the figure's size (an array as a whole, and at least one unit of its own: a figure
that vanishes is compared at the scale of the gait's, as tests/reference_figures.py compares
stored figures); and the exact flow from the plan's start ends within ``END_POINT_BOUND`` (rad) of
the touchdown configuration q_T. The sampled trajectory is a drawing of the step, interpolated
between the grid's nodes: its error is estimated and reported, not bounded (``SAMPLED``).

``IntegrationError`` is a plan's own estimate of how far it is from that (``richardson``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

FIGURE_BOUND = 1e-8  # relative to the figure's size (at least one unit)
END_POINT_BOUND = 1e-9  # rad
GRID_ORDER = 8  # the RK8 grid's: the end state, the solution of the BVP and what the double support makes of them
SAMPLE_ORDER = 5  # the quintic Hermite samples' velocities between the nodes (measured: 31x from 16 to 32 steps)
# The figures under the contract, and the order in the grid's step of the error of each: the
# solution's and the double support's are the grid's; those read from the samples (least, most,
# ranges) carry the interpolation's.
FIGURES: dict[str, int] = {
    **{key: GRID_ORDER for key in (
        "theta", "slack", "W", "heading_change", "I_minus", "I_plus", "IR1_minus", "IR2", "IR2_plus",
        "reaction_spin_impulses", "Xd_minus", "Xd_plus", "Xd_a", "Xd_b", "qd_a", "qd_b", "q0", "qT", "new_stance_foot",
        "H_Tminus", "H_Tplus", "swing_tip_vz_before_impact", "old_stance_tip_vz_after_impact",
        "new_stance_tip_speed_after", "impulse_friction_ratios", "max_intermediate_joint_rate", "foot_line_moment",
        "swing_arrival_speed")},
    **{key: SAMPLE_ORDER for key in (
        "min_grf_z", "min_swing_height", "min_late_swing_height", "max_friction_ratio", "q3_range", "q5_range",
        "q9_min")},
}
SAMPLED = ("q", "qd", "grf", "h_vertical")  # the trajectory's curves (JSON ``trajectory``), at SAMPLE_ORDER


@dataclass(frozen=True)
class IntegrationError:
    """A plan's estimate of its integration error: how far the exact flow from its start ends
    from q_T (``end_point``, rad), and how far from their converged values its effort W
    (``W``), its worst figure (``figures``, the largest over ``FIGURES``) and its sampled
    trajectory (``samples``) are, relative to their size (as ``relative_error``); ``steps``:
    the RK8 steps per T of the grid it was solved on."""

    end_point: float
    W: float
    figures: float
    samples: float
    steps: int

    @property
    def within_contract(self) -> bool:
        """The end point and every figure within the contract's bounds."""
        return self.end_point <= END_POINT_BOUND and self.figures <= FIGURE_BOUND


def relative_error(value: Any, reference: Any) -> float:
    """max |value - reference| / max(largest |reference| entry, 1), an array as a whole: how far
    a figure (a number or an array, as a ``Gait`` holds it) is from a reference value of it; 0
    where both are NaN or the same infinity in the same entries (a figure not computed, or
    unbounded), inf where only one is."""
    if np.ndim(value) == 0 and np.ndim(reference) == 0:  # most figures: a number
        a, b = float(value), float(reference)
        if a == b or (math.isnan(a) and math.isnan(b)):
            return 0.0
        return abs(a - b) / max(abs(b), 1.0) if math.isfinite(a) and math.isfinite(b) else math.inf
    a, b = np.asarray(value, float).ravel(), np.asarray(reference, float).ravel()
    if a.shape != b.shape:
        return math.inf
    differ = ~((a == b) | (np.isnan(a) & np.isnan(b)))
    if not differ.any():
        return 0.0
    if not (np.isfinite(a[differ]).all() and np.isfinite(b[differ]).all()):
        return math.inf
    return float(np.max(np.abs(a[differ] - b[differ])) / max(float(np.max(np.abs(b[np.isfinite(b)]))), 1.0))
