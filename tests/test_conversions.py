"""ROS messages <-> core objects, without a middleware: the GaitPlan message carries every
figure of the core's field list, a walk's orbit survives the message, failures become NaN,
and the constants the offline readers use agree with the generated interfaces."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

pytest.importorskip("biped_gait_interfaces", reason="the ROS interfaces are not built (tools/setup.sh)")

from biped_gait_interfaces.msg import DoubleSupportPhase, GaitEvent, GaitPlan  # noqa: E402
from biped_gait_interfaces.srv import PlanGait  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from std_msgs.msg import Header  # noqa: E402

from biped_gait.core.gait.actuated_swing import ActuatedSwingCycle, SwingEnd, cycle_view  # noqa: E402
from biped_gait.core.gait.configurations import GaitMode  # noqa: E402
from biped_gait.core.gait.lasting_support import LastingSupport  # noqa: E402
from biped_gait.core.gait import views  # noqa: E402
from biped_gait.core.gait.views import FIELDS  # noqa: E402
from biped_gait.core.gait.planner import GaitRequest  # noqa: E402
from biped_gait.core.walking.orbit import PlannedOrbit  # noqa: E402
from biped_gait.recording.topics import MODE_CODES, EventKind  # noqa: E402
from biped_gait.ros.conversions import (OPTION_NAMES, PHASE_NAMES, POINT_NAMES, gait_fields, mode_from_msg,  # noqa: E402
                                        orbit_from_msg, phase_msg, plan_msg, request_from_msg, request_key,
                                        swing_cycle_from_msg, swing_phases_msg, urdf_joints)

pytestmark = pytest.mark.ros


def _as_list(value) -> list:
    if hasattr(value, "x") and hasattr(value, "z"):
        return [value.x, value.y, value.z]
    return list(np.atleast_1d(np.asarray(value, dtype=float)))


def test_every_message_field_of_the_field_list_carries_the_core_value(planner, default_gait):
    joints = urdf_joints(planner.model)
    msg = deserialize_message(serialize_message(plan_msg(default_gait, Header(frame_id="stance_foot"), joints)),
                              GaitPlan)
    checked = 0
    for field in FIELDS:
        if field.msg is None:
            continue
        value = field.read(default_gait)
        got = getattr(msg, field.msg)
        if isinstance(value, str) or (isinstance(value, list) and value and isinstance(value[0], str)):
            assert list(got) == value if isinstance(value, list) else got == value, field.key
        else:
            assert np.allclose(_as_list(got), _as_list(value), rtol=0, atol=0), field.key
        checked += 1
    # every GaitPlan field but the header, the mode code, the reasons and the trajectory with its joint mapping
    trajectory = {"trajectory", "trajectory_stance_side", "joint_roles", "joint_signs", "stride_effort",
                  "double_support_phase", "swing_phases",  # test_the_phase_message_..., test_the_swing_...
                  "start_phase", "stop_phase"}  # test_planner_node's test_the_start_and_stop_are_served_...
    assert checked == len(set(GaitPlan.get_fields_and_field_types()) - {"header", "mode", "reasons"} - trajectory)
    assert mode_from_msg(msg.mode) is GaitMode.NORMAL and list(msg.reasons) == []
    assert len(msg.trajectory.points) == len(default_gait.figures.samples.t)
    assert list(msg.trajectory.joint_names) == list(joints.names) and msg.trajectory_stance_side == "right"
    point = msg.trajectory.points[-1]
    assert np.allclose(point.positions, joints.array(default_gait.figures.samples.q[-1]), atol=0)
    assert np.allclose(point.accelerations, joints.array(default_gait.figures.samples.qdd[-1]), atol=0)
    assert list(point.effort) == [0.0] * 7  # ballistic: no joint torque
    assert list(msg.joint_names) == list(planner.model.names) and len(msg.i_minus) == len(msg.actuated_joints) == 7
    # the stated mapping: URDF angle = sign * the model coordinate it is in this step
    q = default_gait.figures.samples.q[-1]
    for name, sign, angle in zip(msg.joint_roles, msg.joint_signs, point.positions):
        assert angle == sign * q[list(msg.joint_names).index(name)], name


def test_the_phase_message_is_the_plan_jsons_double_support_phase(planner, default_gait):
    """DoubleSupportPhase has every figure of the JSON's double_support_phase and nothing else,
    each carried exactly (arrays flattened row by row, no figure: empty), over serialization: the
    impulsive limit d -> 0+ of the default gait (a tenth of a second; its phase has no samples,
    the node's test reads a lasting one's)."""
    limit = planner.lasting.limit(default_gait)
    phase = views.double_support_phase(limit, limit.effort_total)
    msg = deserialize_message(serialize_message(phase_msg(phase)), DoubleSupportPhase)
    assert_carries(msg, phase)
    assert len(msg.held_impact_impulses) == 6 and len(msg.i_minus) == 7 and list(msg.next_start_velocity) == []


def assert_carries(msg, figures: dict, beyond: tuple[str, ...] = ()) -> None:
    """``msg`` has every figure of the plan JSON's ``figures`` and nothing else but its fields
    ``beyond``, each carried exactly (arrays flattened row by row; none: an empty array, a number NaN)."""
    types = type(msg).get_fields_and_field_types()
    assert {PHASE_NAMES.get(key, key) for key in figures} | set(beyond) == set(types)
    for key, value in figures.items():
        name = PHASE_NAMES.get(key, key)
        got = getattr(msg, name)
        if isinstance(value, (str, bool, int)):
            assert got == value, key
        else:
            none = [] if types[name].startswith("sequence") else math.nan
            assert np.array_equal(np.ravel(got), np.ravel(value if value is not None else none), equal_nan=True), key


def random_cycle(bm, rng: np.random.Generator) -> ActuatedSwingCycle:
    """A cycle whose swing is actuated at its two ends with random figures in ``bm``'s shapes
    (41 samples per end, as the walkable plan's; 5 in the double support), its flight's ends the
    ends' meeting states."""
    nx, na, at = len(bm.ds_names), len(bm.actuated_names), bm.ds_of_single

    def samples(n: int, t0: float, *forces: int) -> list[np.ndarray]:
        return [t0 + np.linspace(0.0, 0.1, n), *rng.normal(size=(3, n, nx)), 200.0 * rng.uniform(-1.0, 1.0, (n, na)),
                rng.uniform(1.0, 2.0, (n, *forces, 3))]

    start, end = SwingEnd(*samples(41, 0.0)), SwingEnd(*samples(41, 0.35))
    support = LastingSupport(0.1, True, "solved", *samples(5, 0.0, 2), np.zeros(na), np.zeros(na),
                             rng.normal(size=(2, 3)), 3.5, 170.0, 3.5, 0, 0.0)
    return ActuatedSwingCycle(0.1, True, "solved", start, end, support, np.concatenate([start.x[-1, at], start.xd[-1, at]]),
                              np.concatenate([end.x[0, at], end.xd[0, at]]), 89.5, 1.1e5, 193, 53.0)


def test_the_swing_phases_message_is_the_plan_jsons_and_gives_the_cycle_back(planner, default_gait):
    """SwingPhases has every figure of the plan JSON's actuated swing (``cycle_view``: its
    swing_phases, each end a SwingPhase, and the cycle's figures) and nothing else, each carried
    exactly over serialization, its double support DoubleSupportPhase's; ``swing_cycle_from_msg``
    gives the cycle back, the flight's ends from the ends' samples; a plan without it gives None. A
    cycle of random figures in the model's shapes (no solve: tests/test_actuated_ros.py reads a
    solved one)."""
    cycle = random_cycle(planner.model, np.random.default_rng(35))
    view = cycle_view(cycle)
    plan = plan_msg(default_gait, Header(), urdf_joints(planner.model))
    assert swing_cycle_from_msg(plan) is None and plan.swing_phases.actuated_swing == 0.0
    plan.swing_phases, plan.double_support_phase = swing_phases_msg(view), phase_msg(view["double_support_phase"])
    plan = deserialize_message(serialize_message(plan), GaitPlan)
    phases = view["swing_phases"]
    figures = {key: value for key, value in view.items() if key not in ("swing_phases", "double_support_phase")}
    assert_carries(plan.swing_phases, {**figures, "success": phases["success"], "message": phases["message"]},
                   beyond=("start", "end"))
    for which in ("start", "end"):
        assert_carries(getattr(plan.swing_phases, which), phases[which])
    assert_carries(plan.double_support_phase, view["double_support_phase"])
    back = swing_cycle_from_msg(plan)
    for which in ("start", "end"):
        for name in ("t", "x", "xd", "xdd", "torques", "contact_forces"):
            assert np.array_equal(getattr(getattr(back, which), name), getattr(getattr(cycle, which), name)), name
    for name in ("t", "x", "xd", "xdd", "torques", "contact_forces", "held_impact_impulses"):
        assert np.array_equal(getattr(back.support, name), getattr(cycle.support, name)), name
    assert np.array_equal(back.flow_start, cycle.flow_start) and np.array_equal(back.flow_end, cycle.flow_end)
    assert np.array_equal(back.peak_torque, cycle.peak_torque) and back.friction_used == cycle.friction_used
    assert (back.actuated_swing, back.success, back.message, back.effort_l1, back.effort_l2, back.iterations,
            back.solve_time_s) == (0.1, True, "solved", 89.5, 1.1e5, 193, 53.0)


def test_the_orbit_a_walk_needs_survives_the_message(planner, default_gait):
    orbit = orbit_from_msg(plan_msg(default_gait, Header(), urdf_joints(planner.model)))
    expected = PlannedOrbit.of(default_gait)
    for name in ("q0", "q_t", "qd_a", "qd_b"):
        assert np.array_equal(getattr(orbit, name), getattr(expected, name)), name
    for name in ("params", "step_length", "period", "arm_amplitude", "mode", "effort", "converged", "admissible", "reasons"):
        assert getattr(orbit, name) == getattr(expected, name), name


def test_a_failed_solve_becomes_nan_and_its_reasons(planner):
    failed = planner.plan(GaitRequest(0.45, 1.5, 0.4))  # its flow diverges: not converged
    msg = plan_msg(failed, Header(), urdf_joints(planner.model))
    assert not msg.converged and list(msg.reasons) == list(failed.reasons) and msg.reasons
    assert math.isnan(msg.effort_cost) and list(msg.i_minus) == [] and math.isnan(msg.ir2.z)
    assert msg.trajectory.points == []
    assert not orbit_from_msg(msg).converged


def test_requests_carry_the_vocabulary_with_0_as_unset_and_unknown_modes_are_refused():
    req = PlanGait.Request(step_length=0.4, period=0.5, arm_amplitude=0.3, mode=PlanGait.Request.ANTI_NORMAL,
                           friction=math.nan, rate_bound=math.inf)
    core = request_from_msg(req, "aoustin2013")
    assert core == dataclasses.replace(GaitRequest(0.4, 0.5, 0.3, GaitMode.ANTI_NORMAL, "aoustin2013"), friction=core.friction)
    assert math.isnan(core.friction) and core.rate_bound == math.inf
    # a field left at the message's 0 means unset where 0 is not a meaningful value
    unset = request_from_msg(PlanGait.Request(), "aoustin2013")
    assert math.isnan(unset.friction) and math.isinf(unset.rate_bound) and math.isnan(unset.step_width)
    assert math.isinf(unset.turn_radius) and unset.min_clearance == 0.0 and unset.friction_margin == 0.0
    key = request_key(gait_fields(req, "aoustin2013", (*POINT_NAMES, *OPTION_NAMES)))
    assert key == request_key(gait_fields(req, "aoustin2013", (*POINT_NAMES, *OPTION_NAMES)))  # NaN keys match
    assert dict(key)["friction"] == "nan" and dict(key)["mode"] == "anti-normal"
    with pytest.raises(ValueError, match="unknown gait mode 7"):
        request_from_msg(PlanGait.Request(mode=7), "aoustin2013")


def test_the_offline_constants_agree_with_the_interfaces():
    assert {kind.name: int(kind) for kind in EventKind} == {
        name: getattr(GaitEvent, name) for name in ("TOUCHDOWN", "FALL", "FINISHED", "NOT_STARTED", "PUSH")}
    assert MODE_CODES == {PlanGait.Request.NORMAL: GaitMode.NORMAL, PlanGait.Request.ANTI_NORMAL: GaitMode.ANTI_NORMAL}


def test_the_interfaces_and_the_simulators_parameters_carry_the_gait_vocabulary():
    """Every option on the service, the action, the recorded call, the echo of the plan and the
    simulator's parameters, with the vocabulary's default wherever a .srv can hold it."""
    from biped_gait.gait_options import OPTIONS, POINT
    from biped_gait.ros.simulator_node import PARAMETERS
    from biped_gait_interfaces.action import OptimizeArmSwing
    from biped_gait_interfaces.msg import PlanGaitCall

    request, goal = PlanGait.Request(), OptimizeArmSwing.Goal()
    fields = set(PlanGait.Request.get_fields_and_field_types())
    assert {o.name for o in (*POINT, *OPTIONS)} <= fields
    assert {o.name for o in OPTIONS} | {"step_length", "period", "alpha_min", "alpha_max", "alpha_step"} <= set(
        OptimizeArmSwing.Goal.get_fields_and_field_types())
    assert fields <= set(PlanGaitCall.get_fields_and_field_types())  # a recorded call holds every field
    assert {"min_clearance", "friction_margin", "within_limits", "friction", "rate_bound"} <= set(
        GaitPlan.get_fields_and_field_types())
    parameters = {p.name: p for p in PARAMETERS}
    for option in (*POINT, *OPTIONS):
        value = option.default
        if option.name in ("mode", "params"):
            continue  # a code on the wire; '' there is the planner's default set
        if isinstance(value, str) or math.isfinite(value):  # a .srv cannot default to NaN or inf
            assert getattr(request, option.name) == value, option.name
            if option.name != "arm_amplitude":
                assert getattr(goal, option.name) == value, option.name
        assert parameters[option.name].default == value or (math.isnan(value) and math.isnan(parameters[option.name].default))
        assert parameters[option.name].choices == option.choices
    assert request.mode == PlanGait.Request.NORMAL and parameters["mode"].default == "normal"
    assert (goal.alpha_min, goal.alpha_max) == pytest.approx((0.0, math.radians(45.0)), abs=1e-15)
    assert goal.alpha_step == pytest.approx(math.radians(1.5), abs=1e-15)
    assert parameters["optimize_arms"].default is False and parameters["arm_amplitude"].low is None  # no sentinel
