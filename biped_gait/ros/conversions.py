"""Translation between ROS messages and the core's request and result objects.

No physics here: field-by-field conversion, units unchanged (SI, radians).
"""

from __future__ import annotations

import math

from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Vector3
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from biped_gait_interfaces.msg import GaitPlan
from biped_gait_interfaces.srv import PlanGait

from ..boundary import GaitMode
from ..gait import GaitRequest
from ..model import JOINT_NAMES
from ..result import GaitResult

MODE_FROM_MSG = {PlanGait.Request.NORMAL: GaitMode.NORMAL, PlanGait.Request.ANTI_NORMAL: GaitMode.ANTI_NORMAL}
MODE_TO_MSG = {mode: code for code, mode in MODE_FROM_MSG.items()}


def mode_from_msg(code: int) -> GaitMode:
    """GaitMode of a message's ``mode`` field; ``ValueError`` for an unknown code."""
    try:
        return MODE_FROM_MSG[code]
    except KeyError:
        raise ValueError(f"unknown gait mode {code}: use NORMAL (0) or ANTI_NORMAL (1)") from None


def request_from_msg(req: PlanGait.Request, default_params: str) -> GaitRequest:
    """The core's GaitRequest for a service request (empty strings take the defaults)."""
    return GaitRequest(
        step_length=req.step_length,
        period=req.period,
        arm_amplitude=req.arm_amplitude,
        mode=mode_from_msg(req.mode),
        params=req.params or default_params,
        closure=req.closure or "theta",
        effort=req.effort or "l1",
    )


def request_key(request: GaitRequest) -> tuple:
    """Hashable identity of a request, for the planner's cache."""
    return (request.step_length, request.period, request.arm_amplitude, GaitMode.parse(request.mode).value,
            request.params, request.closure, request.effort)


def _fixed(values: list[float], size: int) -> list[float]:
    """A fixed-size array field: the values, or NaN where the solve produced none."""
    return [float(v) for v in values] if len(values) == size else [math.nan] * size


def _vector(values: list[float]) -> Vector3:
    x, y, z = _fixed(values, 3)
    return Vector3(x=x, y=y, z=z)


def duration_msg(seconds: float) -> Duration:
    """builtin_interfaces/Duration of a non-negative time in seconds."""
    nanos = int(round(seconds * 1e9))
    return Duration(sec=nanos // 1_000_000_000, nanosec=nanos % 1_000_000_000)


def trajectory_msg(result: GaitResult) -> JointTrajectory:
    """The ballistic step as a JointTrajectory of the model's joints q1..q9 (no header stamp)."""
    traj = JointTrajectory(joint_names=list(JOINT_NAMES))
    samples = result.trajectory
    for t, q, qd in zip(samples.get("t", []), samples.get("q", []), samples.get("qd", [])):
        traj.points.append(JointTrajectoryPoint(positions=list(q), velocities=list(qd), time_from_start=duration_msg(t)))
    return traj


# Fields with the same meaning in GaitResult and GaitPlan: (result attribute, message field).
SCALARS = (
    ("step_length", "step_length"), ("period", "period"), ("arm_amplitude", "arm_amplitude"),
    ("params", "params"), ("closure", "closure"), ("effort", "effort"), ("converged", "converged"),
    ("admissible", "admissible"), ("theta", "theta"), ("slack", "slack"), ("W", "effort_cost"),
    ("min_grf_z", "min_grf_z"), ("min_swing_height", "min_swing_height"),
    ("max_friction_ratio", "max_friction_ratio"), ("closure_residual", "closure_residual"),
    ("solve_time_s", "solve_time"),
)
ARRAYS = (  # (result attribute, message field, fixed size)
    ("I_minus", "i_minus", 7), ("I_plus", "i_plus", 7), ("Xd_minus", "xd_minus", 12), ("Xd_plus", "xd_plus", 12),
    ("Xd_a", "xd_a", 12), ("Xd_b", "xd_b", 12), ("q0", "q0", 9), ("qT", "q_t", 9), ("qd_a", "qd_a", 9),
    ("qd_b", "qd_b", 9), ("H_Tminus", "h_t_minus", 2), ("H_Tplus", "h_t_plus", 2),
)
VECTORS = (("IR1_minus", "ir1_minus"), ("IR2", "ir2"), ("IR2_plus", "ir2_plus"))


def plan_msg(result: GaitResult, header) -> GaitPlan:
    """GaitPlan message of a core result, stamped with ``header``."""
    msg = GaitPlan(header=header, mode=MODE_TO_MSG[GaitMode.parse(result.mode)], reasons=list(result.reasons),
                   trajectory=trajectory_msg(result))
    for attr, name in SCALARS:
        setattr(msg, name, getattr(result, attr))
    for attr, name, size in ARRAYS:
        setattr(msg, name, _fixed(getattr(result, attr), size))
    for attr, name in VECTORS:
        setattr(msg, name, _vector(getattr(result, attr)))
    msg.trajectory.header = header
    return msg


def result_from_plan(msg: GaitPlan) -> GaitResult:
    """The core result of a GaitPlan message (all figures; the trajectory is not copied)."""
    result = GaitResult(step_length=msg.step_length, period=msg.period, arm_amplitude=msg.arm_amplitude,
                        mode=mode_from_msg(msg.mode).value, params=msg.params, closure=msg.closure, effort=msg.effort)
    result.reasons = list(msg.reasons)
    for attr, name in SCALARS:
        setattr(result, attr, getattr(msg, name))
    for attr, name, _ in ARRAYS:
        setattr(result, attr, [float(v) for v in getattr(msg, name)])
    for attr, name in VECTORS:
        v = getattr(msg, name)
        setattr(result, attr, [v.x, v.y, v.z])
    return result
