"""The commands of the README and docs/tutorial.md, as written: every command line of their code
blocks is either run here exactly as the page gives it (from a folder that has the project's
``.venv`` and ``config``, as the repository's folder has), its exit status and a phrase of what
the page says it prints checked, or listed in ``NOT_RUN`` with why (it runs until stopped, it
needs a second terminal, or it is a study of minutes that other tests run on smaller inputs). A
new command in either page fails ``test_every_command_is_run_or_said_why_not`` until it is one or
the other."""

from __future__ import annotations

import math
import os
import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

from biped_gait.core.dynamics.settings import DEFAULTS

pytestmark = pytest.mark.ros  # the launch example walks over DDS

ROOT = Path(__file__).resolve().parents[1]
PAGES = ("README.md", "docs/tutorial.md")

RUN = {
    # command as written: (exit status, a phrase of its output, or alpha* in deg as the page gives it)
    ".venv/bin/biped-gait plan": (0, "admissible True"),
    ".venv/bin/biped-gait plan --out first-plan": (0, "admissible True"),
    ".venv/bin/biped-gait plan --alpha-deg 0": (0, "admissible True"),
    ".venv/bin/biped-gait plan --mode anti-normal": (0, "admissible True"),
    ".venv/bin/biped-gait plan --period 0.35": (1, "swing knee bends backwards"),
    ".venv/bin/biped-gait plan --min-clearance 0.005": (1, "meets the limits but not the margins"),
    ".venv/bin/biped-gait plan --friction-margin 0.1": (0, "admissible True"),
    ".venv/bin/biped-gait plan --rate-bound 12": (0, "admissible True"),
    ".venv/bin/biped-gait plan --double-support 0.1 --json plan.json": (0, "double support of 0.1 s: E ="),
    ".venv/bin/biped-gait plan --start-stop --json plan.json": (0, "stop to standing: 2 s with both feet down"),
    ".venv/bin/biped-gait plan --params aoustin2013-hips --alpha-deg 20": (0, "admissible True"),
    ".venv/bin/biped-gait plan --params aoustin2013-hips --alpha-deg 20 --step-width 0.3 --period 0.5":
        (0, "step width 0.300 m"),
    ".venv/bin/biped-gait plan --params aoustin2013-hips --alpha-deg 20 --turn-radius 2": (0, "admissible True"),
    ".venv/bin/biped-gait check-mujoco": (0, "MuJoCo"),
    ".venv/bin/biped-gait mjcf --out biped.xml": (0, ""),
    ".venv/bin/biped-gait optimize-arms": (0, 23.66),  # alpha* (deg) as the tutorial gives it
    ".venv/bin/biped-gait optimize-arms --friction inf": (0, 27.04),
    ".venv/bin/biped-gait optimize-arms --effort-coordinates absolute --friction inf": (0, 23.89),
    ".venv/bin/biped-gait figure fig4 --out fig4.png": (0, ""),
    ".venv/bin/biped-gait-launch --config config/demo.yaml --analyze": (0, "walk finished: 20 steps"),
}
UNTIL_STOPPED = "runs until stopped (Ctrl-C); the nodes' tests run them with their walks bounded"
NOT_RUN = {
    "bash tools/demo.sh": "the set-up and the demo: CI runs them from a fresh clone",
    "bash tools/test.sh": "this suite",
    ".venv/bin/biped-gait-planner": UNTIL_STOPPED,
    ".venv/bin/biped-gait-simulator --ros-args -p live_view:=true": UNTIL_STOPPED,
    ".venv/bin/biped-gait-simulator --ros-args -p params:=aoustin2013-hips -p arm_amplitude:=0.349 -p turn_radius:=2.0 "
    "-p initial_state:=walking -p live_view:=true": UNTIL_STOPPED,
    ".venv/bin/biped-gait-simulator --ros-args -p initial_state:=walking -p steps:=10 -p arm_amplitude:=0.35 "
    "-p friction_margin:=0.05": UNTIL_STOPPED,
    ".venv/bin/biped-gait-simulator --ros-args -p initial_state:=walking -p steps:=20 -p pushes:=4 0.5 0.5 0 0; "
    "9 0.5 0 -1.0 0": UNTIL_STOPPED,
    ".venv/bin/biped-gait-simulator --ros-args -p double_support:=0.1 -p initial_state:=walking":
        UNTIL_STOPPED + "; test_simulator_lasting.py walks it 20 steps",
    ".venv/bin/biped-gait sweep --step-length 0.40 0.45 0.50 --mode normal anti-normal --out sweep-results":
        "a study of minutes: test_sweep.py runs sweeps on fewer gaits",
    ".venv/bin/biped-gait maps --out maps": "a study of minutes: test_study_cli.py runs maps on a coarser grid",
    ".venv/bin/biped-gait maps --min-clearance 0.005 --out maps-5mm": "a study of minutes: test_study_cli.py",
    ".venv/bin/biped-gait push-study --directions forward backward left right --out push-results":
        "a study of minutes: test_push.py runs push studies on fewer directions",
    "cp biped_gait/core/data/aoustin2013.yaml my-biped.yaml": "your own biped: the atlas build takes minutes",
    ".venv/bin/biped-gait plan --params my-biped.yaml": "your own biped (after the copy and an edit)",
    ".venv/bin/biped-gait atlas build --params my-biped.yaml": "your own biped: minutes on 2 cores; test_atlas.py builds small atlases",
    ".venv/bin/biped-gait optimize-arms --params my-biped.yaml": "your own biped, after its atlas",
    ".venv/bin/biped-gait-planner --ros-args -p default_params:=$PWD/my-biped.yaml": UNTIL_STOPPED,
    ".venv/bin/biped-gait-simulator --ros-args -p params:=$PWD/my-biped.yaml -p initial_state:=walking -p steps:=10":
        UNTIL_STOPPED,
}


def _commands(page: str) -> list[str]:
    """The command lines of a page's indented code blocks (4 spaces), comments dropped, quoting
    undone (as a shell would pass them)."""
    out = []
    for line in (ROOT / page).read_text().splitlines():
        if line.startswith("    ") and not line.startswith("     ") and re.match(r"    (\.venv/bin/|bash |cp )", line):
            out.append(" ".join(shlex.split(line.strip(), comments=True)))
    return out


def test_every_command_is_run_or_said_why_not():
    commands = {c for page in PAGES for c in _commands(page)}
    assert ".venv/bin/biped-gait plan --period 0.35" in commands  # the pages were read
    unaccounted = sorted(commands - set(RUN) - set(NOT_RUN))
    assert not unaccounted, f"commands of the docs neither run nor said why not: {unaccounted}"
    assert not sorted(set(RUN) - commands) and not sorted(set(NOT_RUN) - commands), "listed commands no page has"


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A folder as the repository's: the project's .venv and config (the commands' relative paths)."""
    where = tmp_path_factory.mktemp("doc_examples")
    (where / ".venv").symlink_to(ROOT / ".venv")
    shutil.copytree(ROOT / "config", where / "config")
    return where


@pytest.mark.parametrize("command", sorted(RUN))
def test_the_command_runs_as_written(command, folder):
    status, phrase = RUN[command]
    proc = subprocess.run(shlex.split(command), cwd=folder, capture_output=True, text=True, timeout=600,
                          env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    output = proc.stdout + proc.stderr
    assert proc.returncode == status, output[-3000:]
    if isinstance(phrase, float):  # the page's alpha* to 2 decimals, the optimizer's to its tolerance
        alpha = float(re.search(r"alpha\* = ([0-9.]+) deg", output).group(1))
        assert abs(alpha - phrase) <= 0.005 + math.degrees(DEFAULTS.arm_tolerance), output
    else:
        assert phrase in output, output[-3000:]
