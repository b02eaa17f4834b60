"""Translation between ROS messages and the core's objects. No physics here: field-by-field
conversion driven by the core's field list (``core.gait.views.FIELDS``), units unchanged (SI,
radians). The gait mode is parsed here, at the edge, from the messages' codes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import Vector3
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from biped_gait_interfaces.msg import DoubleSupportPhase, GaitPlan, SwingPhase, SwingPhases
from biped_gait_interfaces.srv import PlanGait

from ..core.gait.configurations import GaitMode
from ..gait_options import OPTIONS, POINT, resolve_unset
from ..core.gait.gait import Gait, Stride
from ..core.gait.lasting_support import LastingSupport
from ..core.gait.views import FIELDS
from ..core.dynamics.impulses import EffortOptions
from ..core.gait.planner import GaitRequest
from ..core.model.biped import BipedModel
from ..core.model.urdf import UrdfJoints
from ..core.walking.orbit import PlannedOrbit
from ..recording.topics import MODE_CODES

if TYPE_CHECKING:
    from ..core.gait.actuated_swing import ActuatedSwingCycle

MODE_TO_MSG = {mode: code for code, mode in MODE_CODES.items()}
POINT_NAMES = tuple(option.name for option in POINT)
OPTION_NAMES = tuple(option.name for option in OPTIONS)
PLAN_STANCE_SIDE = "right"  # a plan's step stands on the model's leg 1, the right foot


def mode_from_msg(code: int) -> GaitMode:
    """GaitMode of a message's ``mode`` field; ``ValueError`` for an unknown code."""
    try:
        return MODE_CODES[code]
    except KeyError:
        raise ValueError(f"unknown gait mode {code}: use NORMAL (0) or ANTI_NORMAL (1)") from None


def gait_fields(msg, default_params: str, names: Sequence[str] = OPTION_NAMES) -> dict[str, object]:
    """The gait vocabulary's fields ``names`` of a request or goal ``msg`` (same names, same
    units) as ``GaitRequest`` fields: the mode parsed from its code, an empty ``params`` the
    node's ``default_params``, and a 0 that means unset replaced by what it stands for
    (``gait_options.resolve_unset``: a message field cannot default to NaN or inf)."""
    fields = resolve_unset({name: getattr(msg, name) for name in names})
    fields["mode"] = mode_from_msg(msg.mode)
    fields["params"] = msg.params or default_params
    return fields


def request_from_msg(req: PlanGait.Request, default_params: str) -> GaitRequest:
    """The core's GaitRequest for a service request."""
    return GaitRequest(**gait_fields(req, default_params, (*POINT_NAMES, *OPTION_NAMES)))


def request_key(fields: dict[str, object]) -> tuple:
    """Hashable identity of request fields, for the planner's caches (NaN equal to NaN)."""
    return tuple((name, "nan" if isinstance(value, float) and math.isnan(value) else
                  value.value if isinstance(value, GaitMode) else value) for name, value in sorted(fields.items()))


def duration_msg(seconds: float) -> Duration:
    """builtin_interfaces/Duration of a non-negative time in seconds."""
    nanos = int(round(seconds * 1e9))
    return Duration(sec=nanos // 1_000_000_000, nanosec=nanos % 1_000_000_000)


def trajectory_msg(gait: Gait, joints: UrdfJoints) -> JointTrajectory:
    """The ballistic step as a JointTrajectory of the URDF's joints (``joints``) with the right
    foot (the model's leg 1) in stance (no header stamp): positions (rad), velocities (rad/s),
    accelerations (rad/s^2) in the URDF's convention, and efforts (N m) zero, as no joint torque
    acts in the ballistic single support."""
    traj = JointTrajectory(joint_names=list(joints.names))
    samples = gait.figures.samples if gait.figures is not None else None
    if samples is not None:
        zero = [0.0] * len(joints.names)
        q, qd, qdd = (joints.array(a, PLAN_STANCE_SIDE) for a in (samples.q, samples.qd, samples.qdd))
        for k, t in enumerate(samples.t):
            traj.points.append(JointTrajectoryPoint(positions=q[k].tolist(), velocities=qd[k].tolist(),
                                                    accelerations=qdd[k].tolist(), effort=zero,
                                                    time_from_start=duration_msg(t)))
    return traj


def _fixed(values, size: int) -> list[float]:
    """A fixed-size array field: the values, or NaN where the solve produced none."""
    return [float(v) for v in values] if len(values) == size else [math.nan] * size


def urdf_joints(bm: BipedModel) -> UrdfJoints:
    """The URDF's moving joints of ``bm`` and where they come from in its coordinates."""
    return UrdfJoints(bm.params.joints, bm.coordinates)


def plan_msg(gait: Gait, header, joints: UrdfJoints) -> GaitPlan:
    """GaitPlan message of a core gait, stamped with ``header``; ``joints``: its model's URDF
    joints (``urdf_joints``)."""
    roles = joints.roles(PLAN_STANCE_SIDE)
    msg = GaitPlan(header=header, mode=MODE_TO_MSG[gait.mode], reasons=list(gait.reasons),
                   trajectory=trajectory_msg(gait, joints), trajectory_stance_side=PLAN_STANCE_SIDE,
                   joint_roles=[name for name, _ in roles], joint_signs=[sign for _, sign in roles])
    for f in FIELDS:
        if f.msg is None:
            continue
        value = f.read(gait)
        if f.vector:
            x, y, z = _fixed(value, 3)
            value = Vector3(x=x, y=y, z=z)
        elif f.size is not None:
            value = _fixed(value, f.size)
        elif f.array or isinstance(value, np.ndarray):
            value = [float(v) for v in value]
        setattr(msg, f.msg, value)
    msg.trajectory.header = header
    msg.stride_effort = gait.W
    return msg


# The plan JSON's double_support_phase keys that DoubleSupportPhase spells otherwise (the others: the same).
PHASE_NAMES = {"X": "x", "Xd": "xd", "Xdd": "xdd", "solve_time_s": "solve_time"}


def figures_msg(msg_type: type, figures: dict):
    """A ``msg_type`` message of a plan JSON's ``figures`` (same names but ``PHASE_NAMES``'):
    arrays flattened row by row, JSON's null NaN again (an empty array where there is none)."""
    msg = msg_type()
    types = msg_type.get_fields_and_field_types()
    for key, value in figures.items():
        name = PHASE_NAMES.get(key, key)
        if types[name].startswith("sequence"):
            value = [] if value is None else np.asarray(value, dtype=float).ravel().tolist()
        elif value is None:
            value = math.nan
        setattr(msg, name, value)
    return msg


def phase_msg(phase: dict) -> DoubleSupportPhase:
    """The DoubleSupportPhase message of a plan JSON's ``double_support_phase``
    (``views.double_support_phase``): the same figures (``figures_msg``)."""
    return figures_msg(DoubleSupportPhase, phase)


def swing_phases_msg(view: dict) -> SwingPhases:
    """The SwingPhases message of a cycle whose swing is actuated at its two ends, as the plan JSON
    has it (``actuated_swing.cycle_view``): its ``swing_phases`` (success, message, each end a
    SwingPhase) and the cycle's figures; its ``double_support_phase`` is ``phase_msg``'s."""
    phases = view["swing_phases"]
    figures = {key: value for key, value in view.items() if key not in ("swing_phases", "double_support_phase")}
    msg = figures_msg(SwingPhases, {**figures, "success": phases["success"], "message": phases["message"]})
    msg.start, msg.end = (figures_msg(SwingPhase, phases[which]) for which in ("start", "end"))
    return msg


def _rows(values, *shape) -> np.ndarray:
    """A flattened array field in its rows of ``shape`` again."""
    return np.asarray(values, dtype=float).reshape(-1, *shape)


def lasting_support_from_msg(plan: GaitPlan) -> LastingSupport | None:
    """What a walk needs of a GaitPlan's double support that lasts (``phase_msg``'s inverse, its
    arrays in their shapes again: ``double_support_coordinates`` and ``actuated_joints`` give
    them); None for the paper's instantaneous one (duration 0)."""
    msg = plan.double_support_phase
    if msg.duration == 0.0:
        return None
    nx, na = len(plan.double_support_coordinates), len(plan.actuated_joints)
    return LastingSupport(
        duration=msg.duration, success=msg.success, message=msg.message, t=np.asarray(msg.t, dtype=float),
        x=_rows(msg.x, nx), xd=_rows(msg.xd, nx), xdd=_rows(msg.xdd, nx), torques=_rows(msg.torques, na),
        contact_forces=_rows(msg.contact_forces, 2, 3), i_minus=np.asarray(msg.i_minus, dtype=float),
        i_plus=np.asarray(msg.i_plus, dtype=float), held_impact_impulses=_rows(msg.held_impact_impulses, 3),
        effort_l1=msg.effort_l1, effort_l2=msg.effort_l2, effort_total=msg.effort_total,
        iterations=msg.iterations, solve_time_s=msg.solve_time,
        next_start_velocity=np.asarray(msg.next_start_velocity, dtype=float),
        push_off=np.asarray(msg.push_off, dtype=float) if len(msg.push_off) else None)


def swing_cycle_from_msg(plan: GaitPlan) -> "ActuatedSwingCycle | None":
    """What a walk needs of a GaitPlan's swing actuated at its two ends (``swing_phases_msg``'s
    inverse, with the double support of ``lasting_support_from_msg``; the ballistic flight's ends
    the actuated ends' meeting states, in the single-support coordinates ``joint_names``); None for
    the paper's ballistic swing (actuated_swing 0)."""
    msg = plan.swing_phases
    if msg.actuated_swing == 0.0:
        return None
    from ..core.gait.actuated_swing import ActuatedSwingCycle, SwingEnd  # CasADi only when asked

    nx, na = len(plan.double_support_coordinates), len(plan.actuated_joints)
    at = [plan.double_support_coordinates.index(name) for name in plan.joint_names]
    start, end = (SwingEnd(np.asarray(m.t, dtype=float), _rows(m.x, nx), _rows(m.xd, nx), _rows(m.xdd, nx),
                           _rows(m.torques, na), _rows(m.contact_forces, 3)) for m in (msg.start, msg.end))
    flow_start, flow_end = (np.concatenate([e.x[k, at], e.xd[k, at]]) for e, k in ((start, -1), (end, 0)))
    return ActuatedSwingCycle(msg.actuated_swing, msg.success, msg.message, start, end, lasting_support_from_msg(plan),
                              flow_start, flow_end, msg.effort_total, msg.effort_l2, msg.iterations, msg.solve_time)


def stride_msgs(stride: Stride, header, joints: UrdfJoints) -> tuple[GaitPlan, list[GaitPlan]]:
    """The GaitPlan messages of a stride's steps: the first (A, right foot) and the others (B),
    each with the stride's effort."""
    plans = [plan_msg(step, header, joints) for step in stride.steps]
    for plan in plans:
        plan.stride_effort = stride.W
    return plans[0], plans[1:]


def orbit_from_msg(msg: GaitPlan) -> PlannedOrbit:
    """What a walk needs of a GaitPlan message."""
    return PlannedOrbit(
        params=msg.params, step_length=msg.step_length, period=msg.period, arm_amplitude=msg.arm_amplitude,
        mode=mode_from_msg(msg.mode), effort=msg.effort, q0=np.array(msg.q0), q_t=np.array(msg.q_t),
        qd_a=np.array(msg.qd_a), qd_b=np.array(msg.qd_b), converged=msg.converged, admissible=msg.admissible,
        reasons=tuple(msg.reasons),
        options=EffortOptions(msg.friction - msg.friction_margin, msg.rate_bound, msg.effort_coordinates or "joint"),
        foot_line_moment=msg.foot_line_moment, theta=msg.theta, turn_radius=msg.turn_radius,
    )
