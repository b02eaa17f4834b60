"""Analysis of a recording (entry point ``biped-gait-analyze``), read from its MCAP file, no
live nodes and no rclpy: ``biped-gait-analyze BAG [--out DIR]``.

BAG is a rosbag2 directory (``metadata.yaml`` and one ``.mcap``) or a bare ``.mcap`` file.
Written to DIR (default ``<bag directory>/analysis``):

- ``summary.json`` and ``summary.md``: duration, topics and message counts; for a walk the
  steps (touchdown time, W, state error, velocity miss from each ``/gait_events`` touchdown),
  falls with their messages, the end of the walk; for a planner recording its calls (count,
  successes, failures with their messages, W of each plan);
- for a walk, PNG plots: the joint angles over the steps (``/joint_states``), the yaw angular
  momentum about the stance foot over two successive steps with the double support marked
  (``/angular_momentum``, as the paper's Fig. 5), and the centre of mass and the stance feet
  seen from above.

Units: times in s from the recording's first message (for a walk: its simulated time),
W (effort_cost) in N m s, state error in rad and rad/s, angles in rad (plots: deg), lengths
in m, angular momentum in kg m^2/s. A missing, unreadable or unfinalized recording prints one
line on stderr and exits with status 2.

``open_bag`` and ``Bag`` (locating and reading a recording) also serve ``biped-gait-replay``;
matplotlib is imported only where the plots are drawn.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from mcap.reader import make_reader
from mcap.records import Channel, Message
from mcap.summary import Summary
from mcap.writer import MCAP0_MAGIC
from mcap_ros2.decoder import DecoderFactory

from .arguments import OneLineParser
from .boundary import GaitMode

PROGRAM = "biped-gait-analyze"
JOINT_TOPIC, MOMENTUM_TOPIC, EVENT_TOPIC = "/joint_states", "/angular_momentum", "/gait_events"
CALL_TYPE = "biped_gait_interfaces/msg/PlanGaitCall"
TOUCHDOWN, FALL, FINISHED = 0, 1, 2  # GaitEvent.kind constants (msg_defs GaitEvent.msg)
MODE_NAMES = {0: GaitMode.NORMAL.value, 1: GaitMode.ANTI_NORMAL.value}  # PlanGait NORMAL, ANTI_NORMAL
LEG_JOINTS = ("hip", "knee")  # joint-name parts drawn in the legs' panel; the others in the upper body's
DPI = 120


class BagError(ValueError):
    """A recording that cannot be read; the message is one line."""


@dataclass(frozen=True)
class Bag:
    """A finalized MCAP recording: the file, its rosbag2 metadata (empty without metadata.yaml)
    and its MCAP summary (channels, schemas, statistics; times in ns)."""

    path: Path
    directory: Path
    metadata: dict
    summary: Summary

    @property
    def start_ns(self) -> int:
        """Log time of the first message (ns)."""
        return self.summary.statistics.message_start_time

    @property
    def duration(self) -> float:
        """From the first to the last message's log time (s)."""
        return (self.summary.statistics.message_end_time - self.start_ns) * 1e-9

    def topics(self) -> dict[str, tuple[str, int]]:
        """Topic -> (type 'pkg/msg/Type', message count), in the order of the channels."""
        counts = self.summary.statistics.channel_message_counts
        topics: dict[str, tuple[str, int]] = {}
        for cid, channel in self.summary.channels.items():
            schema = self.summary.schemas.get(channel.schema_id)
            _, before = topics.get(channel.topic, ("", 0))
            topics[channel.topic] = (schema.name if schema else "", before + counts.get(cid, 0))
        return topics

    def offered_qos(self, topic: str) -> list[dict]:
        """The QoS profiles the recorded publishers of ``topic`` offered (rosbag2 keys:
        history, depth, reliability, durability, ...): from metadata.yaml, else from the MCAP
        channel's metadata (where rosbag2's MCAP plugin keeps them); empty when not recorded."""
        for entry in self.metadata.get("topics_with_message_count", []):
            meta = entry.get("topic_metadata", {})
            if meta.get("name") == topic:
                return _profiles(meta.get("offered_qos_profiles"))
        channel = next((c for c in self.summary.channels.values() if c.topic == topic), None)
        return _profiles(channel.metadata.get("offered_qos_profiles") if channel else None)

    def messages(self, topics: Iterable[str] | None = None) -> Iterator[tuple[Channel, Message]]:
        """The raw records (``Message.data``: CDR bytes) of ``topics`` (all: None) in log-time order."""
        for _, channel, message, _ in self._read(topics, decode=False):
            yield channel, message

    def decoded(self, topics: Iterable[str] | None = None) -> Iterator[tuple[str, float, Any]]:
        """(topic, time in s from the first message, decoded message) in log-time order."""
        for _, channel, message, decoded in self._read(topics, decode=True):
            yield channel.topic, (message.log_time - self.start_ns) * 1e-9, decoded

    def _read(self, topics: Iterable[str] | None, decode: bool) -> Iterator[tuple]:
        try:
            with open(self.path, "rb") as stream:
                reader = make_reader(stream, decoder_factories=[DecoderFactory()])
                topics = None if topics is None else list(topics)
                if decode:
                    yield from reader.iter_decoded_messages(topics=topics, log_time_order=True)
                else:
                    for schema, channel, message in reader.iter_messages(topics=topics, log_time_order=True):
                        yield schema, channel, message, None
        except OSError as exc:
            raise BagError(f"{self.path}: {exc.strerror}") from None
        except Exception as exc:  # noqa: BLE001  a damaged file fails in the reader in many ways
            raise BagError(f"{self.path}: unreadable MCAP data ({type(exc).__name__}: {_one_line(exc)})") from None


def _profiles(value) -> list[dict]:
    """rosbag2 writes the offered profiles as a YAML list, older versions as YAML text."""
    if isinstance(value, str):
        value = yaml.safe_load(value)
    return list(value or [])


def _one_line(exc: Exception) -> str:
    return " ".join(str(exc).split()) or "no details"


def open_bag(path: str | Path) -> Bag:
    """The recording at ``path``: a rosbag2 directory or a bare ``.mcap`` file (its metadata
    then comes from a metadata.yaml beside it that names it). ``BagError`` if it is missing,
    is not MCAP, or was not finalized (no summary)."""
    path = Path(path)
    if path.is_dir():
        metadata = _metadata(path)
        files = metadata.get("relative_file_paths") or sorted(p.name for p in path.glob("*.mcap"))
        if not files:
            raise BagError(f"{path}: no .mcap file in this directory")
        if len(files) > 1:
            raise BagError(f"{path}: {len(files)} MCAP files; only single-file recordings are read")
        mcap_path, directory = path / files[0], path
    elif path.is_file():
        mcap_path, directory = path, path.parent
        metadata = _metadata(directory)
        if path.name not in metadata.get("relative_file_paths", []):
            metadata = {}
    else:
        raise BagError(f"{path}: no such file or directory")
    try:
        with open(mcap_path, "rb") as stream:
            magic = stream.read(len(MCAP0_MAGIC))
            summary = _summary(stream) if magic == MCAP0_MAGIC else None
    except OSError as exc:
        raise BagError(f"{mcap_path}: {exc.strerror}") from None
    if magic != MCAP0_MAGIC:
        raise BagError(f"{mcap_path}: not an MCAP file")
    if summary is None or summary.statistics is None:
        raise BagError(f"{mcap_path}: the recording was not finalized (no MCAP summary); "
                       "'biped-gait recover' rebuilds it")
    return Bag(mcap_path, directory, metadata, summary)


def _summary(stream) -> Summary | None:
    """The MCAP summary of ``stream``; None if it has none."""
    try:
        stream.seek(0)
        return make_reader(stream).get_summary()
    except Exception:  # noqa: BLE001  a truncated file makes the seeking reader fail in several ways
        return None


def _metadata(directory: Path) -> dict:
    """rosbag2_bagfile_information of ``directory/metadata.yaml``; {} if there is none."""
    path = directory / "metadata.yaml"
    if not path.is_file():
        return {}
    try:
        info = yaml.safe_load(path.read_text())["rosbag2_bagfile_information"]
    except (OSError, yaml.YAMLError, TypeError, KeyError):
        raise BagError(f"{path}: not a rosbag2 metadata file") from None
    return info if isinstance(info, dict) else {}


@dataclass
class Walk:
    """The samples and events of a walk recording. Times in s from the recording's start."""

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

    def touchdowns(self) -> list[tuple[float, Any]]:
        return [(t, e) for t, e in self.events if e.kind == TOUCHDOWN]

    def step_starts(self) -> dict[int, tuple[float, str, tuple[float, float, float]]]:
        """Step -> (time, stance side, stance foot) of its first /angular_momentum sample."""
        starts: dict[int, tuple[float, str, tuple[float, float, float]]] = {}
        for t, step, side, foot in zip(self.momentum_time, self.momentum_step, self.stance_side, self.stance_foot):
            starts.setdefault(step, (t, side, foot))
        return starts


def read_walk(bag: Bag) -> Walk | None:
    """The walk in ``bag`` (None if it has none of the walk's topics)."""
    topics = [t for t in (JOINT_TOPIC, MOMENTUM_TOPIC, EVENT_TOPIC) if t in bag.topics()]
    if not topics:
        return None
    walk = Walk()
    for topic, t, msg in bag.decoded(topics):
        if topic == JOINT_TOPIC:
            walk.joint_names = walk.joint_names or list(msg.name)
            by_name = dict(zip(msg.name, msg.position))
            walk.joint_time.append(t)
            walk.joint_positions.append([by_name.get(name, math.nan) for name in walk.joint_names])
        elif topic == MOMENTUM_TOPIC:
            walk.momentum_time.append(t)
            walk.momentum_step.append(msg.step)
            walk.yaw_about_foot.append(msg.about_stance_foot.z)
            walk.com.append((msg.com.x, msg.com.y, msg.com.z))
            walk.stance_foot.append((msg.stance_foot.x, msg.stance_foot.y, msg.stance_foot.z))
            walk.stance_side.append(msg.stance_side)
        else:
            walk.events.append((t, msg))
    return walk


def walk_summary(walk: Walk) -> dict:
    """Steps (one per touchdown event: its time, W, state error, velocity miss), falls, end."""
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
    finished = [e.message for _, e in walk.events if e.kind == FINISHED]
    return {
        "steps": len(steps),
        "effort_cost_per_step": efforts,
        "total_effort_cost": sum(efforts),
        "max_state_error": max((s["state_error"] for s in steps), default=None),
        "max_velocity_miss": max((s["velocity_miss"] for s in steps), default=None),
        "per_step": steps,
        "falls": [{"step": e.step, "time": t, "time_in_step": e.time_in_step, "message": e.message}
                  for t, e in walk.events if e.kind == FALL],
        "finished": finished[-1] if finished else None,
    }


def planner_summary(bag: Bag) -> dict | None:
    """The plan_gait calls recorded by a planner: count, successes, failures, W of each plan."""
    topics = [topic for topic, (datatype, _) in bag.topics().items() if datatype == CALL_TYPE]
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


def summarize(bag: Bag) -> tuple[dict, Walk | None]:
    """The summary of ``bag`` (JSON-ready) and its walk, if it holds one."""
    walk = read_walk(bag)
    summary = {
        "recording": str(bag.path),
        "duration": bag.duration,
        "messages": sum(count for _, count in bag.topics().values()),
        "topics": {topic: {"type": datatype, "messages": count} for topic, (datatype, count) in bag.topics().items()},
        "units": {"time": "s", "effort_cost": "N m s", "state_error": "rad, rad/s", "velocity_miss": "rad/s",
                  "step_length": "m", "period": "s", "arm_amplitude": "rad"},
        "walk": walk_summary(walk) if walk is not None else None,
        "planner": planner_summary(bag),
    }
    return summary, walk


# Plots -------------------------------------------------------------------------------------

def _mark_touchdowns(ax, touchdowns: list[tuple[float, Any]], offset: float = 0.0, label: str = "touchdown") -> None:
    for i, (t, _) in enumerate(touchdowns):
        ax.axvline(t - offset, color="grey", linestyle=":", linewidth=1.0, label=label if i == 0 else None)


def _joint_figure(fig, walk: Walk) -> None:
    """Joint angles (deg) against time, legs above, torso and arms below, touchdowns dotted."""
    legs, upper = fig.subplots(2, 1, sharex=True)
    angles = np.degrees(np.array(walk.joint_positions))
    for j, name in enumerate(walk.joint_names):
        ax = legs if any(part in name for part in LEG_JOINTS) else upper
        ax.plot(walk.joint_time, angles[:, j], label=name)
    for ax, what in ((legs, "legs"), (upper, "torso and arms")):
        _mark_touchdowns(ax, walk.touchdowns())
        ax.set_ylabel(f"{what}: angle (deg)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.01, 0.5))
    upper.set_xlabel("time (s)")
    legs.set_title(f"Joint angles over {len(walk.touchdowns())} steps")


def _momentum_figure(fig, walk: Walk) -> None:
    """Yaw angular momentum about the stance foot over the first two successive steps, the
    double support (instantaneous, at the touchdown) marked; time from the first step's start."""
    ax = fig.add_subplot()
    starts = walk.step_starts()
    first = next((s for s in starts if s + 1 in starts), min(starts))
    shown = [s for s in (first, first + 1) if s in starts]
    step, t, h = np.array(walk.momentum_step), np.array(walk.momentum_time), np.array(walk.yaw_about_foot)
    t0 = starts[first][0]
    for i, s in enumerate(shown):  # one line per step: the jump at the double support stays a jump
        ax.plot(t[step == s] - t0, h[step == s], color=f"C{i}", label=f"step {s}, {starts[s][1]} stance")
    ends = [(td, e) for td, e in walk.touchdowns() if e.step in shown]
    _mark_touchdowns(ax, ends, offset=t0, label="double support (touchdown)")
    ax.axhline(0.0, color="grey", linewidth=0.5)
    ax.set_xlabel(f"time from the start of step {first} (s)")
    ax.set_ylabel("yaw angular momentum about the stance foot (kg m^2/s)")
    ax.set_title(f"Yaw angular momentum, steps {' and '.join(str(s) for s in shown)}")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")


def _top_view_figure(fig, walk: Walk) -> None:
    """The centre of mass's path and the stance feet, x-y plane of the world (m)."""
    ax = fig.add_subplot()
    com = np.array(walk.com)
    ax.plot(com[:, 0], com[:, 1], color="C0", label="centre of mass")
    starts = walk.step_starts()
    for side, marker, colour in (("right", "s", "C1"), ("left", "o", "C2")):
        feet = {step: foot for step, (_, stance, foot) in starts.items() if stance == side}
        if feet:
            ax.plot([f[0] for f in feet.values()], [f[1] for f in feet.values()], marker, color=colour,
                    linestyle="none", label=f"{side} stance foot")
        for step, foot in feet.items():
            ax.annotate(f"step {step}", foot[:2], textcoords="offset points", xytext=(4, 4), fontsize="small")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("Centre of mass and stance feet, seen from above")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")


def write_plots(walk: Walk, out_dir: Path) -> list[Path]:
    """The walk's PNG plots in ``out_dir`` (those its data allow); returns their paths."""
    from matplotlib.figure import Figure  # here: the replay node reads bags through this module

    plots = []
    if walk.joint_time:
        plots.append(("joint_angles.png", _joint_figure, (9.0, 6.5)))
    if walk.momentum_time:
        plots.append(("yaw_momentum_two_steps.png", _momentum_figure, (9.0, 4.6)))
        plots.append(("com_feet_top_view.png", _top_view_figure, (9.0, 4.6)))
    paths = []
    for name, draw, size in plots:
        fig = Figure(figsize=size, layout="constrained")
        draw(fig, walk)
        fig.savefig(out_dir / name, dpi=DPI)
        paths.append(out_dir / name)
    return paths


# Reports -----------------------------------------------------------------------------------

def _walk_lines(walk: dict) -> list[str]:
    end = f"finished ({walk['finished']})" if walk["finished"] else "not finished"
    lines = [f"walk: {walk['steps']} steps, {end}"]
    if walk["steps"]:
        efforts = ", ".join(f"{w:.3f}" for w in walk["effort_cost_per_step"])
        lines.append(f"  W per step (N m s): {efforts} (total {walk['total_effort_cost']:.3f})")
        lines.append(f"  drift from the plan: state error max {walk['max_state_error']:.3g} (rad, rad/s), "
                     f"velocity miss max {walk['max_velocity_miss']:.3g} rad/s")
    falls = [f"  fall in step {f['step']} at {f['time']:.3f} s: {f['message']}" for f in walk["falls"]]
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
                  "| step | touchdown (s) | time in step (s) | W (N m s) | state error | velocity miss (rad/s) |",
                  "|---:|---:|---:|---:|---:|---:|"]
        lines += [f"| {s['step']} | {s['touchdown_time']:.4f} | {s['time_in_step']:.4f} | {s['effort_cost']:.4f} | "
                  f"{s['state_error']:.3g} | {s['velocity_miss']:.3g} |" for s in walk["per_step"]]
        lines.append("")
    lines += ["## Topics", "", "| topic | type | messages |", "|---|---|---:|"]
    lines += [f"| {topic} | {info['type']} | {info['messages']} |" for topic, info in summary["topics"].items()]
    if summary["plots"]:
        lines += ["", "## Plots", ""] + [f"![{Path(p).stem}]({Path(p).name})" for p in summary["plots"]]
    return "\n".join(lines) + "\n"


def analyze(bag: Bag, out_dir: Path) -> dict:
    """Summarize ``bag``, write its plots, summary.json and summary.md to ``out_dir``; returns the summary."""
    summary, walk = summarize(bag)
    out_dir.mkdir(parents=True, exist_ok=True)
    summary["plots"] = [str(p) for p in write_plots(walk, out_dir)] if walk is not None else []
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    (out_dir / "summary.md").write_text(markdown_report(summary))
    return summary


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog=PROGRAM, description="Summarize and plot a recording of biped_gait (walk or planner).")
    parser.add_argument("bag", type=Path, metavar="BAG", help="rosbag2 directory or .mcap file")
    parser.add_argument("--out", type=Path, help="output directory (default: <bag directory>/analysis)")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point ``biped-gait-analyze``; returns the exit status (2: bad recording)."""
    args = _parser().parse_args(argv)
    try:
        bag = open_bag(args.bag)
        out_dir = args.out or bag.directory / "analysis"
        summary = analyze(bag, out_dir)
    except (BagError, OSError) as exc:
        print(f"{PROGRAM}: error: {exc}", file=sys.stderr)
        return 2
    print(text_report(summary))
    if summary["plots"]:
        print("plots:\n" + "\n".join(f"  {p}" for p in summary["plots"]))
    print(f"summary: {out_dir / 'summary.json'}, {out_dir / 'summary.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
