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


def plan_msg(result: GaitResult, header) -> GaitPlan:
    """GaitPlan message of a core result, stamped with ``header``."""
    r = result
    msg = GaitPlan(
        header=header,
        step_length=r.step_length,
        period=r.period,
        arm_amplitude=r.arm_amplitude,
        mode=MODE_TO_MSG[GaitMode.parse(r.mode)],
        params=r.params,
        closure=r.closure,
        effort=r.effort,
        converged=r.converged,
        admissible=r.admissible,
        reasons=list(r.reasons),
        theta=r.theta,
        slack=r.slack,
        effort_cost=r.W,
        i_minus=_fixed(r.I_minus, 7),
        i_plus=_fixed(r.I_plus, 7),
        ir1_minus=_vector(r.IR1_minus),
        ir2=_vector(r.IR2),
        ir2_plus=_vector(r.IR2_plus),
        xd_minus=_fixed(r.Xd_minus, 12),
        xd_plus=_fixed(r.Xd_plus, 12),
        xd_a=_fixed(r.Xd_a, 12),
        xd_b=_fixed(r.Xd_b, 12),
        q0=_fixed(r.q0, 9),
        q_t=_fixed(r.qT, 9),
        qd_a=_fixed(r.qd_a, 9),
        qd_b=_fixed(r.qd_b, 9),
        min_grf_z=r.min_grf_z,
        min_swing_height=r.min_swing_height,
        max_friction_ratio=r.max_friction_ratio,
        h_t_minus=_fixed(r.H_Tminus, 2),
        h_t_plus=_fixed(r.H_Tplus, 2),
        closure_residual=r.closure_residual,
        solve_time=r.solve_time_s,
        trajectory=trajectory_msg(r),
    )
    msg.trajectory.header = header
    return msg


def result_from_plan(msg: GaitPlan) -> GaitResult:
    """The core result a walker needs, from a GaitPlan message (the trajectory is not copied)."""
    mode = mode_from_msg(msg.mode)
    result = GaitResult(
        step_length=msg.step_length,
        period=msg.period,
        arm_amplitude=msg.arm_amplitude,
        mode=mode.value,
        params=msg.params,
        closure=msg.closure,
        effort=msg.effort,
        converged=msg.converged,
        admissible=msg.admissible,
        reasons=list(msg.reasons),
        theta=msg.theta,
        W=msg.effort_cost,
    )
    result.q0, result.qT = list(msg.q0), list(msg.q_t)
    result.qd_a, result.qd_b = list(msg.qd_a), list(msg.qd_b)
    return result
