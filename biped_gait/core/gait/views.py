"""Views of a ``Gait``: its flat figures as one field list (``FIELDS``), which drives the JSON
keys, the sweeps' CSV columns and the ROS ``GaitPlan`` message, and the printed summary.

A new figure is added here once (and to ``GaitPlan.msg`` if the message carries it). Values are
SI with radians; a figure that was not computed (the solve failed before it) is NaN, an empty
list or 0, and null in JSON.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .gait import Gait, Stride

NAN = math.nan


@dataclass(frozen=True)
class Field:
    """One flat figure of a gait: its JSON key, how to read it, and its ``GaitPlan`` field
    (``msg``; None: not in the message): a float64[] of the model's size (``array``; empty where
    the solve produced none), an array of the fixed ``size`` (NaN where the solve produced none)
    or a geometry_msgs/Vector3 (``vector``)."""

    key: str
    read: Callable[[Gait], Any]
    msg: str | None = None
    array: bool = False
    size: int | None = None
    vector: bool = False


def _ds(attr: str, empty: Any = NAN, when: str = "any") -> Callable[[Gait], Any]:
    """A double-support figure; ``when='solved'``: only where its impulse problem was solved."""

    def read(gait: Gait) -> Any:
        ds = gait.double_support
        if ds is None or (when == "solved" and not ds.impulses.success):
            return empty
        return getattr(ds, attr)

    return read


def _impulse(attr: str, empty: Any = ()) -> Callable[[Gait], Any]:
    """A part of the impulse solution (``empty`` where it was not solved)."""

    def read(gait: Gait) -> Any:
        ds = gait.double_support
        return getattr(ds.impulses, attr) if ds is not None and ds.impulses.success else empty

    return read


def _figure(attr: str, empty: Any = NAN) -> Callable[[Gait], Any]:
    return lambda gait: getattr(gait.figures, attr) if gait.figures is not None else empty


def _accuracy(attr: str, empty: Any = NAN) -> Callable[[Gait], Any]:
    """A part of the plan's estimate of its integration error (``empty`` where there is none)."""
    return lambda gait: getattr(gait.accuracy, attr) if gait.accuracy is not None else empty


def _closure_residual(gait: Gait) -> float:
    """z_d^T D_e (Xd^a - Xd^b) (kg m^2/s) as the double support saw it (after the slack
    correction), else the BVP's closure gap."""
    return gait.double_support.impulses.closure_residual if gait.double_support is not None else gait.step.closure_gap


def _trajectory(gait: Gait) -> dict:
    figures = gait.figures
    if figures is None or figures.samples is None:
        return {}
    s = figures.samples
    return {"t": s.t, "q": s.q, "qd": s.qd, "grf": figures.grf, "h_vertical": figures.h_vertical}


FIELDS: tuple[Field, ...] = (
    Field("step_length", lambda g: g.problem.step_length, "step_length"),
    Field("period", lambda g: g.problem.period, "period"),
    Field("arm_amplitude", lambda g: g.problem.arm_amplitude, "arm_amplitude"),
    Field("mode", lambda g: g.problem.mode.value),
    Field("params", lambda g: g.problem.params, "params"),
    Field("closure", lambda g: g.problem.closure, "closure"),
    Field("effort", lambda g: g.problem.effort, "effort"),
    Field("friction", lambda g: g.problem.options.friction, "friction"),
    Field("rate_bound", lambda g: g.problem.options.rate_bound, "rate_bound"),
    Field("effort_coordinates", lambda g: g.problem.options.coordinates, "effort_coordinates"),
    Field("step_width", lambda g: g.problem.step_width, "step_width"),
    Field("turn_radius", lambda g: g.problem.turn_radius, "turn_radius"),
    Field("joint_names", lambda g: list(g.names.joints), "joint_names"),
    Field("actuated_joints", lambda g: list(g.names.actuated), "actuated_joints"),
    Field("double_support_coordinates", lambda g: list(g.names.double_support), "double_support_coordinates"),
    Field("converged", lambda g: g.converged, "converged"),
    Field("admissible", lambda g: g.admissible, "admissible"),
    Field("message", lambda g: g.message),
    Field("reasons", lambda g: list(g.reasons)),
    Field("found", lambda g: g.found, "found"),
    Field("hint", lambda g: g.hint, "hint"),
    Field("theta", lambda g: g.step.theta, "theta"),
    Field("slack", _ds("slack", 0.0), "slack"),
    Field("W", lambda g: g.W, "effort_cost"),
    Field("heading_change", _ds("heading_change"), "heading_change"),
    Field("I_minus", _impulse("i_minus"), "i_minus", array=True),
    Field("I_plus", _impulse("i_plus"), "i_plus", array=True),
    Field("IR1_minus", _impulse("ir1_minus"), "ir1_minus", vector=True),
    Field("IR2", _impulse("ir2"), "ir2", vector=True),
    Field("IR2_plus", _impulse("ir2_plus"), "ir2_plus", vector=True),
    Field("reaction_spin_impulses", _impulse("spin_impulses"), "reaction_spin_impulses", array=True),
    Field("Xd_minus", _impulse("xd_minus"), "xd_minus", array=True),
    Field("Xd_plus", _impulse("xd_plus"), "xd_plus", array=True),
    Field("Xd_a", _ds("xd_a", []), "xd_a", array=True),
    Field("Xd_b", _ds("xd_b", []), "xd_b", array=True),
    Field("qd_a", lambda g: g.step.qd_a, "qd_a", array=True),
    Field("qd_b", lambda g: g.step.qd_b, "qd_b", array=True),
    Field("q0", lambda g: g.step.q0, "q0", array=True),
    Field("qT", lambda g: g.step.q_target, "q_t", array=True),
    Field("new_stance_foot", _ds("new_stance_foot", [])),
    Field("min_grf_z", _figure("min_grf_z"), "min_grf_z"),
    Field("min_swing_height", _figure("min_swing_height"), "min_swing_height"),
    Field("min_late_swing_height", _figure("min_late_swing_height")),
    Field("swing_arrival_speed", _figure("swing_arrival_speed")),
    Field("max_friction_ratio", _figure("max_friction_ratio"), "max_friction_ratio"),
    Field("q3_range", _figure("q3_range", [])),
    Field("q5_range", _figure("q5_range", [])),
    Field("q9_min", _figure("q9_min")),
    Field("H_Tminus", _ds("h_t_minus", []), "h_t_minus", size=2),
    Field("H_Tplus", _ds("h_t_plus", []), "h_t_plus", size=2),
    Field("swing_tip_vz_before_impact", _ds("swing_tip_vz_before_impact", when="solved")),
    Field("old_stance_tip_vz_after_impact", _ds("old_stance_tip_vz_after_impact", when="solved")),
    Field("new_stance_tip_speed_after", _ds("new_stance_tip_speed_after", when="solved")),
    Field("impulse_friction_ratios", _ds("impulse_friction_ratios", [], when="solved"), "impulse_friction_ratios",
          size=3),
    Field("max_intermediate_joint_rate", _ds("max_intermediate_joint_rate", when="solved"),
          "max_intermediate_joint_rate"),
    Field("bvp_iterations", lambda g: g.step.iterations),
    Field("end_point_residual", lambda g: g.step.end_residual),
    Field("closure_residual", _closure_residual, "closure_residual"),
    Field("foot_line_moment", _ds("foot_line_moment", 0.0), "foot_line_moment"),
    Field("impact_equation_residual", _impulse("equation_residual", NAN)),
    Field("lp_duality_gap", _impulse("duality_gap", NAN)),
    Field("energy_drift", _figure("energy_drift")),
    # The plan's estimate of its integration error (docs/model.md section 4.11) and its grid.
    Field("integration_error_end_point", _accuracy("end_point")),
    Field("integration_error_W", _accuracy("W")),
    Field("integration_error_figures", _accuracy("figures")),
    Field("integration_error_samples", _accuracy("samples")),
    Field("grid_steps", _accuracy("steps", 0)),
    Field("dynamics_evaluations", lambda g: g.step.evaluations),
    Field("multipliers", lambda g: [[v.real, v.imag] for v in g.stability.values] if g.stability else []),
    Field("multiplier_moduli", lambda g: np.abs(g.stability.values) if g.stability else [], "multiplier_moduli"),
    Field("spectral_radius", lambda g: g.stability.spectral_radius if g.stability else NAN, "spectral_radius"),
    Field("open_loop_stable", lambda g: g.stability.stable if g.stability else False, "open_loop_stable"),
    Field("solve_time_s", lambda g: g.solve_time_s, "solve_time"),
    Field("trajectory", _trajectory),
    # The margins asked and whether the gait meets the limits (it may miss the margins).
    Field("min_clearance", lambda g: g.problem.margins.clearance, "min_clearance"),
    Field("friction_margin", lambda g: g.problem.margins.friction, "friction_margin"),
    Field("within_limits", lambda g: g.within_limits, "within_limits"),
)
FIELD_BY_KEY = {f.key: f for f in FIELDS}


def clean(value: Any) -> Any:
    """JSON-ready: arrays and tuples to lists, NaN and infinities to None."""
    if isinstance(value, np.ndarray):
        return clean(value.tolist())
    if isinstance(value, (list, tuple)):
        return [clean(v) for v in value]
    if isinstance(value, dict):
        return {k: clean(v) for k, v in value.items()}
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def to_dict(gait: Gait, trajectory: bool = True) -> dict:
    """The gait's flat figures as a JSON-ready dictionary, in ``FIELDS`` order."""
    return {f.key: clean(f.read(gait)) for f in FIELDS if trajectory or f.key != "trajectory"}


def double_support_phase(support, limit_effort: float) -> dict:
    """A double support that lasts (``lasting_support.LastingSupport``) as the plan's JSON has it, in the
    plan's ``double_support_coordinates`` and ``actuated_joints``; ``limit_effort`` E(0+) (N m s)."""
    return clean({
        "duration": support.duration, "success": support.success, "message": support.message,
        "t": support.t, "X": support.x, "Xd": support.xd, "Xdd": support.xdd, "torques": support.torques,
        "contact_forces": support.contact_forces, "effort_l1": support.effort_l1, "effort_l2": support.effort_l2,
        "peak_torque": support.peak_torque, "friction_used": support.friction_used, "i_minus": support.i_minus,
        "i_plus": support.i_plus, "held_impact_impulses": support.held_impact_impulses,
        "effort_total": support.effort_total, "effort_impulsive_limit": limit_effort,
        "next_start_velocity": support.next_start_velocity, "push_off": support.push_off, "iterations": support.iterations,
        "solve_time_s": support.solve_time_s})


def to_json(gait: Gait, trajectory: bool = True) -> str:
    """JSON text of ``to_dict``."""
    return json.dumps(to_dict(gait, trajectory), indent=1)


def summary(gait: Gait) -> str:
    """A readable multi-line summary (degrees where people expect them)."""
    deg = math.degrees
    d = {f.key: f.read(gait) for f in FIELDS if f.key != "trajectory"}
    lines = [
        f"gait  L = {gait.step_length:.3f} m, T = {gait.period:.3f} s, alpha = {deg(gait.arm_amplitude):.2f} deg, "
        f"{d['mode']}, params {d['params']}, closure {d['closure']}, effort {d['effort']}",
        f"converged {gait.converged} ({d['bvp_iterations']} Newton iterations, found by {gait.found}), "
        f"admissible {gait.admissible}",
    ]
    margins = gait.problem.margins.text(gait.problem.options.rate_bound)
    if margins:
        lines.append(f"margins: {margins}")
    lines += [f"  not admissible: {r}" for r in gait.reasons]
    if gait.hint:
        lines.append(f"  {gait.hint}")
    if gait.converged and math.isfinite(gait.W):
        fmt = lambda v: "[" + ", ".join(f"{x:8.3f}" for x in v) + "]"  # noqa: E731
        lines += [
            f"W = {gait.W:.4f} N m s    theta = {deg(gait.theta):.4f} deg    step width {gait.problem.step_width:.3f} m"
            + (f"    s = {d['slack']:.6f} rad/s" if d["closure"] == "slack" else ""),
            f"joint impulses on {', '.join(gait.names.actuated)}:",
            f"I-  (N m s) {fmt(d['I_minus'])}",
            f"I+  (N m s) {fmt(d['I_plus'])}",
            f"I_R1- {fmt(d['IR1_minus'])}  I_R2 {fmt(d['IR2'])}  I_R2+ {fmt(d['IR2_plus'])}  (N s)"
            + (f"  spin {fmt(d['reaction_spin_impulses'])} (N m s)" if len(d["reaction_spin_impulses"]) else ""),
            f"min vertical GRF {d['min_grf_z']:.2f} N, min swing height {d['min_swing_height'] * 1000:.1f} mm, "
            f"max friction ratio {d['max_friction_ratio']:.3f}",
            f"q3 in [{deg(d['q3_range'][0]):.3f}, {deg(d['q3_range'][1]):.3f}] deg, "
            f"q5 in [{deg(d['q5_range'][0]):.3f}, {deg(d['q5_range'][1]):.3f}] deg",
            f"yaw angular momentum (kg m^2/s) about old/new stance foot: T- {d['H_Tminus'][0]:.3f}/{d['H_Tminus'][1]:.3f}, "
            f"T+ {d['H_Tplus'][0]:.3f}/{d['H_Tplus'][1]:.3f}",
            f"residuals: BVP end {d['end_point_residual']:.1e} rad, closure {d['closure_residual']:.1e} kg m^2/s, "
            f"impact eqs {d['impact_equation_residual']:.1e}, LP duality {d['lp_duality_gap']:.1e}, "
            f"energy drift {d['energy_drift']:.1e}",
        ]
    if gait.accuracy is not None:
        e = gait.accuracy
        lines.append(f"integration error (estimated, {e.steps} RK8 steps): end point {e.end_point:.1e} rad, W {e.W:.1e}, "
                     f"figures {e.figures:.1e} (relative), samples {e.samples:.1e}; "
                     f"{'within' if e.within_contract else 'beyond'} the contract")
    if gait.stability is not None:
        moduli = ", ".join(f"{m:.3g}" for m in np.abs(gait.stability.values[:6]))
        lines.append(f"open-loop Floquet multipliers |lambda| {moduli}, ...: spectral radius "
                     f"{gait.stability.spectral_radius:.4g}, {'stable' if gait.stability.stable else 'unstable'}")
    timed = "" if math.isnan(gait.solve_time_s) else f"solve time {gait.solve_time_s * 1000:.1f} ms, "  # a stride's steps: timed with it
    lines.append(f"{timed}{d['dynamics_evaluations']} dynamics evaluations")
    return "\n".join(lines)


def stride_to_dict(stride: Stride, trajectory: bool = True) -> dict:
    """A stride's figures (radius m, heading change rad per stride, W N m s per stride and per
    metre walked, outcome, the stride's open-loop multipliers) and each step's (``to_dict``)."""
    moduli = np.abs(stride.stability.values) if stride.stability else []
    return clean({
        "turn_radius": stride.radius, "heading_change_per_stride": stride.heading_change, "W_per_stride": stride.W,
        "W_per_metre": stride.W / (2 * stride.problem.step_length), "converged": stride.converged,
        "admissible": stride.admissible, "reasons": list(stride.reasons), "found": stride.found, "hint": stride.hint,
        "multiplier_moduli": moduli, "spectral_radius": stride.stability.spectral_radius if stride.stability else NAN,
        "solve_time_s": stride.solve_time_s, "steps": [to_dict(step, trajectory) for step in stride.steps],
    })


def stride_to_json(stride: Stride, trajectory: bool = True) -> str:
    """JSON text of ``stride_to_dict``."""
    return json.dumps(stride_to_dict(stride, trajectory), indent=1)


def stride_summary(stride: Stride) -> str:
    """A readable summary of a stride and of each of its steps."""
    head = [
        f"stride on a circle of radius {stride.radius:.3f} m ({'left' if stride.radius > 0 else 'right'} turn): "
        f"heading change {math.degrees(stride.heading_change):.2f} deg per stride of two steps, found by {stride.found}",
        f"admissible {stride.admissible}, W = {stride.W:.4f} N m s per stride "
        f"({stride.W / (2 * stride.problem.step_length):.3f} N s per metre walked)",
    ]
    head += [f"  not admissible: {r}" for r in stride.reasons]
    if stride.hint:
        head.append(f"  {stride.hint}")
    if stride.stability is not None:
        head.append(f"open-loop spectral radius of the stride {stride.stability.spectral_radius:.4g}")
    head.append(f"solve time {stride.solve_time_s * 1000:.1f} ms")
    for name, step in zip(("A, right foot", "B, left foot"), stride.steps):
        head += ["", f"step {name}:", summary(step)]
    return "\n".join(head)
