"""The results page's section on the walk (docs/model.md section 8): the Floquet multipliers of
the Fig. 4 gaits against alpha with the walker's closed loop, the largest push recovered against
alpha and direction, and a ramp of commanded speeds 0.6 -> 1.2 -> 0.6 m/s with the effort per
step. Computed on an executor when the page is generated; the page calls ``compute_walking``,
``walking_figures`` and ``walking_section``.

L in m, T in s, alpha in rad (degrees on the page), impulses in N s, W in N m s.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, replace

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..core.gait.configurations import GaitMode
from ..core.gait.gait import Gait
from ..core.model.params import BipedParams
from ..core.gait.planner import GaitRequest
from ..core.dynamics.settings import DEFAULTS
from ..core.gait.stability import closed_loop
from ..core.walking.steering import DEFAULT_RATE
from ..core.walking.transitions import follower_for
from ..core.walking.orbit import PlannedOrbit
from ..core.walking.runner import Walker
from .executors import planner_for
from .push_study import (PHASE, RECOVERY_STEPS, RECOVERY_TOLERANCE, PushedGait, PushLimit, limit_vs_alpha_figure,
                         polar_figure, run_push_study)
from .study import FIG4_STEP_LENGTHS, FIG5_CASE, Study
from ..core.gait.chains import inclusive_range

ALPHA_STEP = math.radians(5.0)  # rad: the default spacing of the alphas of the closed loops and the pushes
AXIS_DIRECTIONS = ("forward", "backward", "left", "right")
DIAGONALS = ("forward-left", "backward-left", "backward-right", "forward-right")
RAMP_SPEEDS = (0.6, 1.2)  # m/s: from, to and back
RAMP_HOLD = 8  # steps at each end of the ramp
RAMP_RATE = 0.03  # m/s per step: the command's ramp (the follower allows 0.05)


@dataclass(frozen=True)
class ClosedLoop:
    """The closed-loop spectral radius of the walker at (L m, alpha rad), with the plain re-aim
    (``steering`` None) or momentum steering at that rate."""

    step_length: float
    alpha: float
    steering: float | None
    radius: float


@dataclass(frozen=True)
class RampStep:
    """One step of the speed ramp: commanded speed, speed of the gait aimed at, measured speed
    (stance-foot advance over the step's duration; m/s), the aimed gait (L m, T s), W (N m s),
    and the CPU time of the step with its transition (s; 0 without one)."""

    commanded: float
    aimed: float
    measured: float
    step_length: float
    period: float
    W: float
    transition_seconds: float


@dataclass(frozen=True, eq=False)
class Walking:
    """What the section shows: the Fig. 4 gaits (with their multipliers), the closed loops, the
    push limits (steered, and plain at alpha*), alpha* (rad), the ramp and the speed rule."""

    curves: list[Gait]
    loops: list[ClosedLoop]
    pushes: list[PushLimit]
    plain_pushes: list[PushLimit]
    alpha_opt: float
    ramp: list[RampStep]
    rule: str
    note: str


def closed_loop_radius(params: BipedParams, step_length: float, period: float, alpha: float,
                       steering: float | None) -> ClosedLoop:
    """Worker entry: the walker's closed-loop spectral radius on the gait, by differences."""
    planner = planner_for(params)
    gait = planner.plan(GaitRequest(step_length, period, alpha, GaitMode.NORMAL))
    orbit = PlannedOrbit.of(gait)

    def walker_at(q, qd):
        walker = Walker(planner.hybrid, orbit, rate=1.0, momentum_rate=steering)
        walker.state = replace(walker.state, q=q, qd=qd)
        return walker

    loop = closed_loop(walker_at, np.concatenate([gait.step.q0, gait.step.qd_a]))
    return ClosedLoop(step_length, alpha, steering, loop.spectral_radius)


def speed_ramp(params: BipedParams, alpha: float, speeds: tuple[float, float] = RAMP_SPEEDS,
               hold: int = RAMP_HOLD) -> tuple[list[RampStep], str, str]:
    """Walk a ramp of commanded speeds with the simulator's walker and speed follower, from the
    gait L = T = 0.45 s at ``alpha`` (rad): the first speed until the follower is there and
    ``hold`` steps more, a ramp of ``RAMP_RATE`` per step to the second, ``hold`` steps there,
    and back likewise; returns the steps from the first hold on, the rule's description and the
    follower's note ('' if none)."""
    planner = planner_for(params)
    gait = planner.plan(GaitRequest(0.45, 0.45, alpha, GaitMode.NORMAL))
    walker = Walker(planner.hybrid, PlannedOrbit.of(gait), rate=50.0, momentum_rate=DEFAULT_RATE)
    follower, note = follower_for(walker, DEFAULTS)
    settle = max(math.ceil(abs(follower.speed - speeds[0]) / follower.max_change),  # speed and period there
                 math.ceil(abs(follower.orbit.period - follower.rule.gait(speeds[0]).period) / follower.max_period_change))
    ramp = list(np.linspace(*speeds, math.ceil(abs(speeds[1] - speeds[0]) / RAMP_RATE) + 1))
    schedule = [speeds[0]] * (settle + hold) + ramp + [speeds[1]] * hold + ramp[::-1] + [speeds[0]] * hold
    steps = []
    for command in schedule:
        follower.command(float(command))
        start = time.process_time()
        transition = follower.before_step(walker)
        foot = walker.state.stance_foot[0]
        outcome = walker.walk_step()
        if outcome.touchdown is None:
            raise RuntimeError(f"the speed ramp fell in step {walker.state.step}: {outcome.fall}")
        cpu = time.process_time() - start if transition is not None else 0.0
        td = outcome.touchdown
        steps.append(RampStep(float(command), follower.speed, (walker.state.stance_foot[0] - foot) / td.t_step,
                              follower.orbit.step_length, follower.orbit.period, td.W, cpu))
    return steps[settle:], follower.rule.describe(), note


def compute_walking(executor: Executor, study: Study, alpha_step: float = ALPHA_STEP,
                    directions: Sequence[str] = (*AXIS_DIRECTIONS, *DIAGONALS)) -> Walking:
    """The section's numbers for ``study``'s parameter set (the default one), on ``executor``:
    closed loops and pushes every ``alpha_step`` (rad) over [0, 45] deg, the pushes in
    ``directions`` (names of ``push_study.STUDY_DIRECTIONS``; about 5 s of CPU time each
    direction and alpha: the section's cost)."""
    params = study.params
    alpha_opt = study.comparisons[FIG5_CASE].optimum.alpha
    length, period = FIG5_CASE
    alphas = inclusive_range(0.0, math.radians(45.0), alpha_step, "arm amplitude")
    axes = [d for d in AXIS_DIRECTIONS if d in directions]
    diagonals = [d for d in DIAGONALS if d in directions]
    loops = [executor.submit(closed_loop_radius, params, L, period, a, s)
             for L in FIG4_STEP_LENGTHS for a in alphas for s in (None, DEFAULT_RATE)]
    ramp = executor.submit(speed_ramp, params, alpha_opt)
    cases = [(a, d) for a in alphas for d in axes]
    cases += [(a, d) for a in (0.0, alpha_opt) for d in diagonals] + [(alpha_opt, d) for d in axes]
    pushed = PushedGait(params, length, period, GaitMode.NORMAL.value)
    pushes = run_push_study(executor, pushed, cases)
    plain = run_push_study(executor, replace(pushed, steering=None), [(alpha_opt, d) for d in axes])
    steps, rule, note = ramp.result()
    return Walking(list(study.curves), [f.result() for f in loops], pushes, plain, alpha_opt, steps, rule, note)


# Figures -------------------------------------------------------------------------------------

def _figure(rows: int = 1, columns: int = 2, width: float = 5.2) -> tuple[Figure, np.ndarray]:
    fig = Figure(figsize=(width * columns, 3.6 * rows + 0.6), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, np.array([[fig.add_subplot(rows, columns, r * columns + c + 1) for c in range(columns)]
                          for r in range(rows)])


def multipliers_figure(walking: Walking) -> Figure:
    """Left: the moduli of the four largest open-loop multipliers of the normal gait against
    alpha for each Fig. 4 L (T = 0.45 s). Right: the walker's closed-loop spectral radius,
    plain re-aim and momentum steering. A colour per L, a line style per multiplier (left) or
    re-aim (right), each said once in the legends."""
    fig, [[left, right]] = _figure()
    ranks = ("-", "--", ":", "-.")
    loops = ((None, "--", "plain re-aim"), (DEFAULT_RATE, "-", f"momentum steering rho = {DEFAULT_RATE:g}"))
    for i, length in enumerate(FIG4_STEP_LENGTHS):
        gaits = sorted((g for g in walking.curves if g.step_length == length and g.mode is GaitMode.NORMAL
                        and g.stability is not None), key=lambda g: g.arm_amplitude)
        moduli = np.array([np.abs(g.stability.values[:4]) for g in gaits]).reshape(len(gaits), 4)
        for rank, style in enumerate(ranks):
            left.plot([math.degrees(g.arm_amplitude) for g in gaits], moduli[:, rank], style, color=f"C{i}")
        for steering, style, _ in loops:
            curve = sorted((lp for lp in walking.loops if lp.step_length == length and lp.steering == steering),
                           key=lambda lp: lp.alpha)
            right.plot([math.degrees(lp.alpha) for lp in curve], [lp.radius for lp in curve], style, marker=".",
                       color=f"C{i}")
    lengths = [Line2D([], [], color=f"C{i}", linewidth=3, label=f"L = {length:g} m")
               for i, length in enumerate(FIG4_STEP_LENGTHS)]
    left.legend(handles=lengths + [Line2D([], [], color="k", linestyle=style, label=f"|lambda_{rank + 1}|")
                                   for rank, style in enumerate(ranks)], fontsize="x-small", ncols=2, handlelength=3)
    right.legend(handles=lengths + [Line2D([], [], color="k", linestyle=style, marker=".", label=label)
                                    for _, style, label in loops], fontsize="x-small", handlelength=3)
    left.set_yscale("log")
    left.set_title("Open-loop Floquet multipliers |lambda_1..4|, T = 0.45 s", fontsize="medium")
    right.set_yscale("log")
    right.set_title("Closed loop of the walker: spectral radius", fontsize="medium")
    for ax in (left, right):
        ax.set_xlabel("arm amplitude alpha (deg)")
        ax.grid(True, alpha=0.3, which="both")
    return fig


def ramp_figure(walking: Walking) -> Figure:
    """The speed ramp: commanded, aimed and measured speed per step (top), W per step and per
    metre (bottom)."""
    fig, axes = _figure(2, 1, width=9.0)
    top, bottom = axes[0, 0], axes[1, 0]
    steps = np.arange(len(walking.ramp))
    top.plot(steps, [s.commanded for s in walking.ramp], "k--", label="commanded (/cmd_vel)")
    top.plot(steps, [s.aimed for s in walking.ramp], "C0-", drawstyle="steps-post", label="gait aimed at (L / T)")
    top.plot(steps, [s.measured for s in walking.ramp], "C1.", label="walked (foot advance / step duration)")
    top.set_ylabel("speed (m/s)")
    top.legend(fontsize="small")
    bottom.plot(steps, [s.W for s in walking.ramp], "C2.-", label="W per step (N m s)")
    twin = bottom.twinx()
    twin.plot(steps, [s.W / (s.measured * s.period) for s in walking.ramp], "C3.", label="W per metre (N s)")
    bottom.set_xlabel("step")
    bottom.set_ylabel("W per step (N m s)", color="C2")
    twin.set_ylabel("W per metre walked (N s)", color="C3")
    top.set_title(f"Speed ramp {RAMP_SPEEDS[0]:g} -> {RAMP_SPEEDS[1]:g} -> {RAMP_SPEEDS[0]:g} m/s, alpha = "
                  f"{math.degrees(walking.alpha_opt):.2f} deg, {walking.rule.split(':')[0]}", fontsize="medium")
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
    return fig


def walking_figures(walking: Walking, params: str) -> dict[str, tuple[Figure, str]]:
    """Caption -> (figure, file name) of the section."""
    at = [p for p in walking.pushes if p.alpha in (0.0, walking.alpha_opt)]
    axes = [p for p in walking.pushes if p.direction in AXIS_DIRECTIONS]
    title = f"L = T = 0.45, push at {PHASE:g} T, params {params}"
    return {
        f"Floquet multipliers against alpha and the walker's closed loop, parameter set {params}":
            (multipliers_figure(walking), "walk-multipliers.png"),
        f"Largest push recovered against alpha, parameter set {params}":
            (limit_vs_alpha_figure(axes, f"Largest push recovered, {title}"), "walk-push-alpha.png"),
        f"Largest push recovered per direction, no arm swing and the optimal one, parameter set {params}":
            (polar_figure(at, f"Largest push recovered, {title}"), "walk-push-polar.png"),
        f"A ramp of commanded speeds with the effort per step, parameter set {params}":
            (ramp_figure(walking), "walk-speed-ramp.png"),
    }


# Text ----------------------------------------------------------------------------------------

def _push_table(walking: Walking) -> list[str]:
    rows = []
    for direction in (*AXIS_DIRECTIONS, *DIAGONALS):
        values = []
        for limits, alpha in ((walking.pushes, 0.0), (walking.pushes, walking.alpha_opt), (walking.plain_pushes,
                                                                                            walking.alpha_opt)):
            found = [p for p in limits if p.direction == direction and p.alpha == alpha]
            values.append(f"{found[0].limit:.3g}" if found else "-")
        rows.append(f"| {direction} | " + " | ".join(values) + " |")
    return [f"| direction | alpha = 0 | alpha* = {math.degrees(walking.alpha_opt):.2f} deg | alpha*, plain re-aim |",
            "|---|---|---|---|", *rows]


def _sides(at_opt: dict[str, float]) -> str:
    """Which side takes the larger push at alpha* (N s by direction), if both were pushed."""
    if not {"left", "right"} <= at_opt.keys():
        return ""
    side = ("to the left, towards the swing foot's side, than to the right, over the stance foot"
            if at_opt["left"] > at_opt["right"] else "to the right, over the stance foot, than to the left")
    return f" The walker takes larger pushes {side} ({at_opt['left']:.3g} against {at_opt['right']:.3g} N s at alpha*)."


def walking_section(walking: Walking, figures: dict[str, str]) -> list[str]:
    """The section's Markdown lines; ``figures`` maps its captions to paths."""
    steered = [lp.radius for lp in walking.loops if lp.steering is not None]
    plain = [lp.radius for lp in walking.loops if lp.steering is None]
    lengths = ", ".join(f"{L:.2f}" for L in sorted({lp.step_length for lp in walking.loops}))
    alphas = sorted({math.degrees(lp.alpha) for lp in walking.loops})
    alpha_text = f"{alphas[0]:g} to {alphas[-1]:g} deg" if len(alphas) > 1 else f"{alphas[0]:g} deg"
    open_loop = [g.stability.spectral_radius for g in walking.curves if g.stability is not None]
    transitions = [s.transition_seconds for s in walking.ramp if s.transition_seconds > 0]
    top = max(walking.ramp, key=lambda s: s.aimed)
    low = min(walking.ramp[-RAMP_HOLD:], key=lambda s: abs(s.measured - RAMP_SPEEDS[0]))
    lines = ["", "## The walk: stability, pushes, commanded speed", "",
             "The walker of the simulator (docs/model.md section 8) on the default parameter set. Open loop (the "
             "impulses held), every ballistic gait is unstable: a perturbation grows by the spectral radius of the "
             "Poincare map each step. The walker's per-step re-aim closes the loop; with the duration as its only "
             "extra unknown one mode, the momentum about the foot-to-foot line that no impulse can change, decays "
             "about 1 % per step; momentum steering (section 8.7) frees the next touchdown's trunk pitch and makes "
             f"that error contract by rho = {DEFAULT_RATE:g} per step.", "",
             f"- **Open loop**: spectral radius {min(open_loop):.0f} to {max(open_loop):.0f} over the Fig. 4 gaits "
             "(both modes). **Closed loop**: "
             f"{min(plain):.4f} to {max(plain):.4f} with the plain re-aim, {min(steered):.4f} to {max(steered):.4f} "
             f"with steering (by differences of the walker's step, L = {lengths} m, alpha {alpha_text}).",
             f"- **Pushes** (a horizontal impulse on the trunk at mid-step of a right-foot step, `biped-gait "
             f"push-study`): recovered if the robot does not fall and, {RECOVERY_STEPS} steps after the pushed one, "
             f"its state at the step's start is within {RECOVERY_TOLERANCE:g} (rad, rad/s) of the orbit's. The "
             "largest push by a scan up from 0.05 N s by factors 1.5 and bisection to 2 %; the recovered "
             "magnitudes need not form an interval (the re-aim's boundary-value problem has folds), so each figure "
             "is the largest below which every push tried was recovered (N s):", ""]
    lines += _push_table(walking)
    at_opt = {p.direction: p.limit for p in walking.pushes if p.alpha == walking.alpha_opt}
    lines += ["", "The pushes are small: the single support is ballistic, so a push acts uncorrected until the next "
              "touchdown, amplified by the open-loop instability over half a step; the re-aim and the impulses can "
              "then only correct what reaches the double support (pushes fail by a re-aim without solution or a "
              "double support whose impulse LP is infeasible)." + _sides(at_opt) + " Failures of the first push not "
              "recovered, per direction at alpha*: "
              + "; ".join(f"{p.direction} {p.first_failure:.3g} N s, {p.failure}" for p in walking.pushes
                          if p.alpha == walking.alpha_opt and p.direction in AXIS_DIRECTIONS) + ".", "",
              f"- **Commanded speed** ({walking.rule}"
              + (f"; {walking.note}" if walking.note else "") + f"): a ramp of /cmd_vel from {RAMP_SPEEDS[0]:g} to "
              f"{RAMP_SPEEDS[1]:g} m/s and back, {RAMP_RATE:g} m/s per step, one transition step per change of "
              f"the aimed gait. The fastest gait aimed at: L = {top.step_length:.3f} m, "
              f"T = {top.period:.3f} s; back at {RAMP_SPEEDS[0]:g} m/s the walk measures {low.measured:.4f} m/s. "
              f"{len(transitions)} transition steps, CPU time each (the new gait's orbit, the re-aim, impulses and "
              f"integration) median {1e3 * np.median(transitions):.1f} ms, max {1e3 * max(transitions):.1f} ms.", ""]
    lines += [f"![{caption}]({path})\n\n*{caption}*\n" for caption, path in figures.items()]
    return lines
