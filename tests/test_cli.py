"""The ``biped-gait`` command as a user runs it: a real subprocess of the installed entry point."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.core

ENTRY = shutil.which("biped-gait", path=str(Path(sys.executable).parent))


def run(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess:
    assert ENTRY, "the biped-gait entry point is not installed in this environment"
    return subprocess.run([ENTRY, *args], capture_output=True, text=True, timeout=timeout)


def test_plan_defaults_prints_a_converged_admissible_gait(tmp_path):
    out = tmp_path / "gait.json"
    proc = run("plan", "--json", str(out))
    assert proc.returncode == 0, proc.stderr
    assert "converged True" in proc.stdout and "admissible True" in proc.stdout
    assert "W = " in proc.stdout and "theta = " in proc.stdout
    data = json.loads(out.read_text())
    assert data["converged"] and data["admissible"] and data["W"] > 0


@pytest.mark.parametrize("unbuffered", ["1", ""])
@pytest.mark.parametrize("args", [["plan", "--out", "X"], ["plan", "--json", "-"]])
def test_a_closed_standard_output_is_no_error(tmp_path, args, unbuffered):
    """``plan --out X | head -3`` as a reader that is gone before the first line (and each line
    written at once, or at the end): nothing is said of the pipe, the plan's files are written
    and its exit status is its own, as with a Unix tool whose reader stopped reading."""
    read, write = os.pipe()
    os.close(read)
    try:
        proc = subprocess.run([ENTRY, *args], stdout=write, stderr=subprocess.PIPE, text=True, timeout=120,
                              cwd=tmp_path, env={**os.environ, "PYTHONUNBUFFERED": unbuffered})
    finally:
        os.close(write)
    assert proc.returncode == 0, proc.stderr
    assert not any(word in proc.stderr for word in ("biped-gait: error", "Broken pipe", "Exception", "Traceback")), proc.stderr
    if "--out" in args:
        assert proc.stderr == ""
        assert (tmp_path / "X" / "plan.json").is_file() and (tmp_path / "X" / "plan.png").is_file()


def test_plan_and_help_import_only_what_they_use():
    """No plotting, progress bars, MCAP, study modules, OSQP, SciPy's optimize or the strides'
    modules for one straight gait or a verb's help (they cost a plan process more than its solve)."""
    heavy = ("matplotlib", "tqdm", "mcap", "osqp", "scipy.optimize", "scipy.sparse", "dask", "rclpy",
             "biped_gait.studies.study", "biped_gait.studies.maps", "biped_gait.studies.results_page",
             "biped_gait.core.gait.stride", "biped_gait.core.gait.turning_atlas")
    for argv in (["plan"], ["sweep", "--help"], ["push-study", "--help"], ["atlas", "build", "--help"]):
        code = ("import contextlib, io, sys\nfrom biped_gait.cli import main\n"
                f"with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit): main({argv!r})\n"
                f"print(sorted(name for name in sys.modules if name.split('.')[0] in {heavy!r} or name in {heavy!r}))")
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.strip() == "[]", (argv, proc.stdout)


def test_a_verb_parsed_alone_is_the_verb_of_the_whole_parser():
    """``biped-gait VERB`` builds that verb's parser only: every verb of the whole parser is in
    ``ADDERS``, and its help is the same built alone."""
    from biped_gait.cli_parser import ADDERS, build_parser

    def verbs(parser) -> dict:
        action = next(a for a in parser._actions if a.dest == "command")
        return {name: sub.format_help() for name, sub in action.choices.items()}

    whole = verbs(build_parser())
    assert set(whole) == set(ADDERS)
    for verb in ADDERS:
        assert verbs(build_parser(verb))[verb] == whole[verb]


def test_plan_options_reach_the_core():
    proc = run("plan", "--step-length", "0.40", "--alpha-deg", "20", "--mode", "anti-normal",
               "--params", "aoustin2013-table", "--closure", "slack", "--effort", "l2")
    assert proc.returncode == 0, proc.stderr
    assert "anti-normal, params aoustin2013-table, closure slack, effort l2" in proc.stdout
    assert "s = " in proc.stdout


@pytest.mark.parametrize(
    "args, message",
    [
        (["--step-length", "2.0"], "step length must be in (0, 1.814) m"),
        (["--step-length", "nan"], "step length must be a finite number"),
        (["--period", "-0.4"], "period must be positive"),
        (["--alpha-deg", "90"], "arm amplitude must be in [0, 90) deg, got 90 deg"),
        (["--alpha-deg", "inf"], "arm amplitude must be a finite number"),
        (["--mode", "hop"], "argument --mode: invalid choice: 'hop'"),
        (["--params", "no-such-set"], "unknown parameter set 'no-such-set'"),
    ],
)
def test_bad_input_is_one_line_and_a_nonzero_exit(args, message):
    proc = run("plan", *args)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0]
    assert proc.stdout == ""


def test_bad_parameter_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nlinks: {}\ngeometry: {}\n")
    proc = run("plan", "--params", str(bad))
    assert proc.returncode == 2 and "missing value links.shin" in proc.stderr


def test_urdf_command_writes_a_robot(tmp_path):
    out = tmp_path / "biped.urdf"
    proc = run("urdf", "--out", str(out))
    assert proc.returncode == 0
    text = out.read_text()
    for joint in ("right_hip", "left_knee", "torso_yaw", "left_shoulder"):
        assert f'<joint name="{joint}" type="revolute">' in text
