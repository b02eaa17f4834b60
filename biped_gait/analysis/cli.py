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

Units: a walk's times in s from its first sample (its start; ``walk_start``: that sample after the
recording's first message),
W (effort_cost) in N m s, state error in rad and rad/s, angles in rad (plots: deg), lengths
in m, angular momentum in kg m^2/s. A missing, unreadable or unfinalized recording prints one
line on stderr and exits with status 2.

The recording is read by ``recording.reader``, summarized by ``summaries`` and drawn by ``plots``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..arguments import OneLineParser
from ..recording.reader import Bag, BagError, open_bag
from .plots import write_plots
from .summaries import markdown_report, summarize, text_report

PROGRAM = "biped-gait-analyze"


def analyze(bag: Bag, out_dir: Path) -> dict:
    """Summarize ``bag``, write its plots, summary.json and summary.md to ``out_dir``; returns the summary."""
    summary, walk = summarize(bag)
    out_dir.mkdir(parents=True, exist_ok=True)
    summary["plots"] = [str(p) for p in write_plots(walk, out_dir)] if walk is not None else []
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    (out_dir / "summary.md").write_text(markdown_report(summary))
    return summary


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog=PROGRAM, description="Summarize and plot a recording of biped_gait (walk or planner).")
    parser.add_argument("bag", type=Path, metavar="BAG", help="rosbag2 directory or .mcap file")
    parser.add_argument("--out", type=Path, help="output directory (default: <bag directory>/analysis)")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point ``biped-gait-analyze``; returns the exit status (2: bad recording)."""
    args = build_parser().parse_args(argv)
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
