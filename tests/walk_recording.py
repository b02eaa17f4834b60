"""A short walk recorded by a simulator against a planner of the test's own (renamed, so that
no other test's planner answers), for the replay and analysis tests."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from .ros_helpers import start_node, stop_node


@contextmanager
def own_planner(where: Path, name: str, record: bool = False) -> Iterator[None]:
    """A planner node named ``name``, recording (if ``record``) under ``where/planner_bags``;
    stopped with SIGTERM at the end, which must exit 0."""
    proc = start_node("biped-gait-planner", "-r", f"__node:={name}", "-p", f"record:={str(record).lower()}",
                      "-p", f"record_dir:={where / 'planner_bags'}", cwd=where)
    try:
        yield
    finally:
        assert stop_node(proc) == 0, (where / "biped-gait-planner.log").read_text()


def record_walk(where: Path, planner: str, steps: int) -> Path:
    """Walk ``steps`` steps as fast as possible on the plan of ``planner``; the recording's directory."""
    proc = start_node("biped-gait-simulator", "-p", f"plan_service:=/{planner}/plan_gait",
                      "-p", f"optimize_action:=/{planner}/optimize_arm_swing", "-p", "initial_state:=walking",
                      "-p", f"steps:={steps}",
                      "-p", "real_time_factor:=0.0", "-p", "exit_when_done:=true",
                      "-p", f"record_dir:={where / 'bags'}", cwd=where)
    assert proc.wait(timeout=120) == 0, (where / "biped-gait-simulator.log").read_text()
    [bag] = list((where / "bags").iterdir())
    return bag
