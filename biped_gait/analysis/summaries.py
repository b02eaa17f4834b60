"""Summaries of a recording: the walk it holds (joint states, angular momentum, gait events)
and the planner calls, as JSON-ready dictionaries and as text and Markdown reports.

Units: a walk's times in s from its first sample (its start: the walk's simulated time 0; the
recording begins earlier, with the robot's description and the plan), the recording's duration in s,
W (effort_cost) in N m s, state error in rad and rad/s, angles in rad, lengths in m, angular
momentum in kg m^2/s.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..recording.reader import Bag
from ..recording.topics import ANGULAR_MOMENTUM, GAIT_EVENTS, JOINT_STATES, MODE_NAMES, PLAN_CALL_TYPE, EventKind


@dataclass
class WalkRecording:
    """The samples and events of a walk recording. Times in s from the walk's first sample (its
    start), which is ``start`` s after the recording's first message."""

    joint_names: list[str] = field(default_factory=list)
    joint_time: list[float] = field(default_factory=list)
    joint_positions: list[list[float]] = field(default_factory=list)  # rad, one row per sample
    momentum_time: list[float] = field(default_factory=list)
    momentum_step: list[int] = field(default_factory=list)
    yaw_about_foot: list[float] = field(default_factory=list)  # kg m^2/s, about the stance foot tip
    com: list[tuple[float, float, float]] = field(default_factory=list)  # m, world
    stance_foot: list[tuple[float, float, float]] = field(default_factory=list)  # m, world
    stance_side: list[str] = field(default_factory=list)
    events: list[tuple[float, Any]] = field(default_factory=list)  # (time, GaitEvent)
    start: float = 0.0  # s: the walk's first sample after the recording's first message

    def touchdowns(self) -> list[tuple[float, Any]]:
        return [(t, e) for t, e in self.events if e.kind == EventKind.TOUCHDOWN]

    def step_starts(self) -> dict[int, tuple[float, str, tuple[float, float, float]]]:
        """Step -> (time, stance side, stance foot) of its first /angular_momentum sample."""
        starts: dict[int, tuple[float, str, tuple[float, float, float]]] = {}
        for t, step, side, foot in zip(self.momentum_time, self.momentum_step, self.stance_side, self.stance_foot):
            starts.setdefault(step, (t, side, foot))
        return starts


def read_walk(bag: Bag) -> WalkRecording | None:
    """The walk in ``bag`` (None if it has none of the walk's topics)."""
    topics = [t for t in (JOINT_STATES, ANGULAR_MOMENTUM, GAIT_EVENTS) if t in bag.topics()]
    if not topics:
        return None
    walk = WalkRecording()
    for topic, t, msg in bag.decoded(topics):
        if topic == JOINT_STATES:
            walk.joint_names = walk.joint_names or list(msg.name)
            by_name = dict(zip(msg.name, msg.position))
            walk.joint_time.append(t)
            walk.joint_positions.append([by_name.get(name, math.nan) for name in walk.joint_names])
        elif topic == ANGULAR_MOMENTUM:
            walk.momentum_time.append(t)
            walk.momentum_step.append(msg.step)
            walk.yaw_about_foot.append(msg.about_stance_foot.z)
            walk.com.append((msg.com.x, msg.com.y, msg.com.z))
            walk.stance_foot.append((msg.stance_foot.x, msg.stance_foot.y, msg.stance_foot.z))
            walk.stance_side.append(msg.stance_side)
        else:
            walk.events.append((t, msg))
    samples = walk.joint_time[:1] + walk.momentum_time[:1]
    walk.start = min(samples) if samples else 0.0
    walk.joint_time = [t - walk.start for t in walk.joint_time]
    walk.momentum_time = [t - walk.start for t in walk.momentum_time]
    walk.events = [(t - walk.start, e) for t, e in walk.events]
    return walk


def walk_summary(walk: WalkRecording) -> dict:
    """Steps (one per touchdown event: its time, W, state error, velocity miss), pushes, falls, end."""
    steps = [{
        "step": e.step,
        "touchdown_time": t,
        "time_in_step": e.time_in_step,
        "effort_cost": e.effort_cost,
        "state_error": e.state_error,
        "velocity_miss": e.velocity_miss,
        "next_stance_side": e.stance_side,
    } for t, e in walk.touchdowns()]
    efforts = [s["effort_cost"] for s in steps]
    finished = [e.message for _, e in walk.events if e.kind == EventKind.FINISHED]
    return {
        "steps": len(steps),
        "effort_cost_per_step": efforts,
        "total_effort_cost": sum(efforts),
        "max_state_error": max((s["state_error"] for s in steps), default=None),
        "median_state_error": statistics.median(s["state_error"] for s in steps) if steps else None,
        "max_state_error_step": max(steps, key=lambda s: s["state_error"])["step"] if steps else None,
        "max_velocity_miss": max((s["velocity_miss"] for s in steps), default=None),
        "per_step": steps,
        "pushes": [{"step": e.step, "time": t, "time_in_step": e.time_in_step, "message": e.message}
                   for t, e in walk.events if e.kind == EventKind.PUSH],
        "falls": [{"step": e.step, "time": t, "time_in_step": e.time_in_step, "message": e.message}
                  for t, e in walk.events if e.kind == EventKind.FALL],
        "finished": finished[-1] if finished else None,
    }


def planner_summary(bag: Bag) -> dict | None:
    """The plan_gait calls recorded by a planner: count, successes, failures, W of each plan."""
    topics = [topic for topic, (datatype, _) in bag.topics().items() if datatype == PLAN_CALL_TYPE]
    if not topics:
        return None
    calls = [msg for _, _, msg in bag.decoded(topics)]
    plans = [{
        "sequence": c.sequence,
        "step_length": c.plan.step_length,
        "period": c.plan.period,
        "arm_amplitude": c.plan.arm_amplitude,
        "mode": MODE_NAMES.get(c.plan.mode, str(c.plan.mode)),
        "effort_cost": c.plan.effort_cost,
        "admissible": c.plan.admissible,
        "message": c.message,
    } for c in calls if c.success]
    return {
        "calls": len(calls),
        "successes": len(plans),
        "failures": [{"sequence": c.sequence, "message": c.message} for c in calls if not c.success],
        "plans": plans,
    }


def summarize(bag: Bag) -> tuple[dict, WalkRecording | None]:
    """The summary of ``bag`` (JSON-ready) and its walk, if it holds one."""
    walk = read_walk(bag)
    summary = {
        "recording": str(bag.path),
        "duration": bag.duration,
        "messages": sum(count for _, count in bag.topics().values()),
        "topics": {topic: {"type": datatype, "messages": count} for topic, (datatype, count) in bag.topics().items()},
        "units": {"time": "s from the walk's first sample", "effort_cost": "N m s", "state_error": "rad, rad/s", "velocity_miss": "rad/s",
                  "step_length": "m", "period": "s", "arm_amplitude": "rad"},
        "walk": walk_summary(walk) if walk is not None else None,
        "walk_start": walk.start if walk is not None else None,
        "planner": planner_summary(bag),
    }
    return summary, walk


# Reports -----------------------------------------------------------------------------------

def _walk_lines(walk: dict) -> list[str]:
    end = f"finished ({walk['finished']})" if walk["finished"] else "not finished"
    lines = [f"walk: {walk['steps']} steps, {end}"]
    if walk["steps"]:
        efforts = ", ".join(f"{w:.3f}" for w in walk["effort_cost_per_step"])
        lines.append(f"  W per step (N m s): {efforts} (total {walk['total_effort_cost']:.3f})")
        lines.append(f"  touchdowns against the gait each step aimed at (the plan, or a transition's gait): state "
                     f"error (the larger of the joint angles' error in rad and the joint rates' in rad/s) median "
                     f"{walk['median_state_error']:.3g}, largest {walk['max_state_error']:.3g} (step "
                     f"{walk['max_state_error_step']}); unreachable velocity at most {walk['max_velocity_miss']:.3g} rad/s")
    lines += [f"  {p['message']}" for p in walk["pushes"]]
    falls = [f"  fall in step {f['step']} at {f['time']:.3f} s of the walk: {f['message']}" for f in walk["falls"]]
    lines += falls or ["  falls: none"]
    return lines


def _planner_lines(planner: dict) -> list[str]:
    lines = [f"planner: calls to plan_gait {planner['calls']}, succeeded {planner['successes']}, "
             f"failed {len(planner['failures'])}"]
    lines += [f"  call {p['sequence']}: W = {p['effort_cost']:.3f} N m s (L = {p['step_length']:g} m, "
              f"T = {p['period']:g} s, alpha = {math.degrees(p['arm_amplitude']):.2f} deg, {p['mode']})"
              for p in planner["plans"]]
    lines += [f"  call {f['sequence']} failed: {f['message']}" for f in planner["failures"]]
    return lines


def text_report(summary: dict) -> str:
    """The short summary printed by the command."""
    lines = [f"recording: {summary['recording']} ({summary['duration']:.3f} s, {summary['messages']} messages "
             f"on {len(summary['topics'])} topics)"]
    if summary["walk"] is not None:
        lines += _walk_lines(summary["walk"])
    if summary["planner"] is not None:
        lines += _planner_lines(summary["planner"])
    return "\n".join(lines)


def markdown_report(summary: dict) -> str:
    """summary.md: the text report, the steps and topics as tables, the plots."""
    lines = [f"# Analysis of {Path(summary['recording']).name}", "", "```", text_report(summary), "```", ""]
    walk = summary["walk"]
    if walk and walk["per_step"]:
        lines += ["## Steps", "",
                  "| step | touchdown (s from the walk's start) | time in step (s) | W (N m s) | state error (rad or rad/s) | velocity miss (rad/s) |",
                  "|---:|---:|---:|---:|---:|---:|"]
        lines += [f"| {s['step']} | {s['touchdown_time']:.4f} | {s['time_in_step']:.4f} | {s['effort_cost']:.4f} | "
                  f"{s['state_error']:.3g} | {s['velocity_miss']:.3g} |" for s in walk["per_step"]]
        lines.append("")
    lines += ["## Topics", "", "| topic | type | messages |", "|---|---|---:|"]
    lines += [f"| {topic} | {info['type']} | {info['messages']} |" for topic, info in summary["topics"].items()]
    if summary["plots"]:
        lines += ["", "## Plots", ""] + [f"![{Path(p).stem}]({Path(p).name})" for p in summary["plots"]]
    return "\n".join(lines) + "\n"
