"""The result of one gait solve, its admissibility verdict, JSON form and printed summary.

All values SI, angles in radians (the summary also shows degrees). Velocities in extended
coordinates X = [x0, y0, z0, q1..q9] are in this step's frame: stance leg 1 on the right,
stance tip at the world origin.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field

import numpy as np

# Admissibility margins: a figure counts as positive when above these (N, m).
GRF_MARGIN = 0.0
HEIGHT_MARGIN = 0.0
KNEE_TOLERANCE = 1e-9  # rad: q9 >= -this is the human-like branch


def _clean(value):
    """JSON-ready: arrays to lists, NaN and infinities to None."""
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


@dataclass
class GaitResult:
    """Every figure of one gait (spec section 6). Lists are plain Python for JSON."""

    step_length: float
    period: float
    arm_amplitude: float
    mode: str
    params: str
    closure: str
    effort: str
    converged: bool = False
    admissible: bool = False
    message: str = ""
    reasons: list[str] = field(default_factory=list)
    theta: float = math.nan
    slack: float = 0.0
    W: float = math.nan
    I_minus: list[float] = field(default_factory=list)
    I_plus: list[float] = field(default_factory=list)
    IR1_minus: list[float] = field(default_factory=list)
    IR2: list[float] = field(default_factory=list)
    IR2_plus: list[float] = field(default_factory=list)
    Xd_minus: list[float] = field(default_factory=list)
    Xd_plus: list[float] = field(default_factory=list)
    Xd_a: list[float] = field(default_factory=list)
    Xd_b: list[float] = field(default_factory=list)
    qd_a: list[float] = field(default_factory=list)
    qd_b: list[float] = field(default_factory=list)
    q0: list[float] = field(default_factory=list)
    qT: list[float] = field(default_factory=list)
    new_stance_foot: list[float] = field(default_factory=list)
    min_grf_z: float = math.nan
    min_swing_height: float = math.nan
    max_friction_ratio: float = math.nan
    q3_range: list[float] = field(default_factory=list)
    q5_range: list[float] = field(default_factory=list)
    q9_min: float = math.nan
    H_Tminus: list[float] = field(default_factory=list)
    H_Tplus: list[float] = field(default_factory=list)
    swing_tip_vz_before_impact: float = math.nan
    old_stance_tip_vz_after_impact: float = math.nan
    new_stance_tip_speed_after: float = math.nan
    bvp_iterations: int = 0
    end_point_residual: float = math.nan
    closure_residual: float = math.nan
    impact_equation_residual: float = math.nan
    lp_duality_gap: float = math.nan
    energy_drift: float = math.nan
    dynamics_evaluations: int = 0
    solve_time_s: float = math.nan
    trajectory: dict = field(default_factory=dict)

    @classmethod
    def empty(cls, request, step_length: float, period: float, alpha: float, mode, params_name: str) -> "GaitResult":
        """A result for a validated request, before anything is solved."""
        return cls(
            step_length=step_length,
            period=period,
            arm_amplitude=alpha,
            mode=mode.value,
            params=params_name,
            closure=request.closure,
            effort=request.effort,
        )

    def fill_bvp(self, bvp) -> None:
        """Copy the shooting's outcome (``bvp.BvpSolution``)."""
        self.converged = bvp.converged
        self.message = "" if bvp.converged else f"ballistic BVP: {bvp.message}"
        self.theta = bvp.theta
        self.q0, self.qT = bvp.q0.tolist(), bvp.q_target.tolist()
        self.qd_a, self.qd_b = bvp.qd_a.tolist(), bvp.qd_b.tolist()
        self.bvp_iterations = bvp.iterations
        self.end_point_residual = bvp.end_residual
        self.closure_residual = bvp.closure_gap
        self.dynamics_evaluations = bvp.evaluations

    def fill_impulses(self, sol, xd_b: np.ndarray, xd_a: np.ndarray, slack: float) -> None:
        """Copy the double support's solution (``impulses.ImpulseSolution``)."""
        self.Xd_b, self.Xd_a, self.slack = xd_b.tolist(), xd_a.tolist(), slack
        self.closure_residual = sol.closure_residual
        if not sol.success:
            self.message = sol.message
            return
        self.W = sol.W
        self.I_minus, self.I_plus = sol.i_minus.tolist(), sol.i_plus.tolist()
        self.IR1_minus, self.IR2, self.IR2_plus = sol.ir1_minus.tolist(), sol.ir2.tolist(), sol.ir2_plus.tolist()
        self.Xd_minus, self.Xd_plus = sol.xd_minus.tolist(), sol.xd_plus.tolist()
        self.impact_equation_residual = sol.equation_residual
        self.lp_duality_gap = sol.duality_gap

    def fill_step(self, traj, figures, energy_drift: float) -> None:
        """Copy the single support's samples (``reports.StepTrajectory``) and figures."""
        self.min_grf_z = figures.min_grf_z
        self.min_swing_height = figures.min_swing_height
        self.max_friction_ratio = figures.max_friction_ratio
        self.q3_range, self.q5_range = list(figures.q3_range), list(figures.q5_range)
        self.q9_min = figures.q9_min
        self.energy_drift = energy_drift
        self.trajectory = {
            "t": traj.t.tolist(),
            "q": traj.q.tolist(),
            "qd": traj.qd.tolist(),
            "grf": figures.grf.tolist(),
            "h_vertical": figures.h_vertical.tolist(),
        }

    def judge(self) -> None:
        """Set ``admissible`` and the reasons it is not (spec section 4, items 2 and 4)."""
        reasons = []
        if not self.converged:
            reasons.append(self.message or "the ballistic BVP did not converge")
        elif not math.isfinite(self.W):
            reasons.append(self.message or "the impulse problem has no solution")
        else:
            if not self.min_grf_z > GRF_MARGIN:
                reasons.append(f"vertical ground reaction not positive (min {self.min_grf_z:.3g} N)")
            if not self.min_swing_height > HEIGHT_MARGIN:
                reasons.append(f"swing tip touches or enters the ground (min height {self.min_swing_height:.3g} m)")
            if not self.q9_min >= -KNEE_TOLERANCE:
                reasons.append(f"swing knee bends backwards (min q9 {math.degrees(self.q9_min):.3g} deg)")
        self.reasons = reasons
        self.admissible = not reasons

    def to_dict(self, trajectory: bool = True) -> dict:
        """Plain JSON-ready dictionary (NaN as null)."""
        data = asdict(self)
        if not trajectory:
            data.pop("trajectory")
        return _clean(data)

    def to_json(self, trajectory: bool = True) -> str:
        """JSON text of ``to_dict``."""
        return json.dumps(self.to_dict(trajectory), indent=1)

    def summary(self) -> str:
        """A readable multi-line summary (degrees where people expect them)."""
        deg = math.degrees
        lines = [
            f"gait  L = {self.step_length:.3f} m, T = {self.period:.3f} s, alpha = {deg(self.arm_amplitude):.2f} deg, "
            f"{self.mode}, params {self.params}, closure {self.closure}, effort {self.effort}",
            f"converged {self.converged} ({self.bvp_iterations} Newton iterations), admissible {self.admissible}",
        ]
        if self.reasons:
            lines += [f"  not admissible: {r}" for r in self.reasons]
        if self.converged and math.isfinite(self.W):
            fmt = lambda v: "[" + ", ".join(f"{x:8.3f}" for x in v) + "]"  # noqa: E731
            lines += [
                f"W = {self.W:.4f} N m s    theta = {deg(self.theta):.4f} deg"
                + (f"    s = {self.slack:.6f} rad/s" if self.closure == "slack" else ""),
                f"I-  (N m s) {fmt(self.I_minus)}",
                f"I+  (N m s) {fmt(self.I_plus)}",
                f"I_R1- {fmt(self.IR1_minus)}  I_R2 {fmt(self.IR2)}  I_R2+ {fmt(self.IR2_plus)}  (N s)",
                f"min vertical GRF {self.min_grf_z:.2f} N, min swing height {self.min_swing_height * 1000:.1f} mm, "
                f"max friction ratio {self.max_friction_ratio:.3f}",
                f"q3 in [{deg(self.q3_range[0]):.3f}, {deg(self.q3_range[1]):.3f}] deg, "
                f"q5 in [{deg(self.q5_range[0]):.3f}, {deg(self.q5_range[1]):.3f}] deg",
                f"yaw angular momentum (kg m^2/s) about old/new stance foot: T- {self.H_Tminus[0]:.3f}/{self.H_Tminus[1]:.3f}, "
                f"T+ {self.H_Tplus[0]:.3f}/{self.H_Tplus[1]:.3f}",
                f"residuals: BVP end {self.end_point_residual:.1e} rad, closure {self.closure_residual:.1e} kg m^2/s, "
                f"impact eqs {self.impact_equation_residual:.1e}, LP duality {self.lp_duality_gap:.1e}, "
                f"energy drift {self.energy_drift:.1e}",
            ]
        lines.append(f"solve time {self.solve_time_s * 1000:.1f} ms, {self.dynamics_evaluations} dynamics evaluations")
        return "\n".join(lines)
