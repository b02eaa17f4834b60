"""The study commands as a user runs them (the installed ``biped-gait`` entry point in a
subprocess): sweeps and their files, bad input, Ctrl-C, optimize-arms, figures, results page."""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import signal
import subprocess
import time

import pytest

from .test_cli import ENTRY, run
from .test_actuated_page import STORED as ACTUATED_STUDY, check_actuated_section
from .test_lasting_page import STORED as LASTING_STUDY, check_lasting_section

pytestmark = pytest.mark.studies

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def test_sweep_writes_csv_json_and_figures(tmp_path):
    out = tmp_path / "out"
    proc = run("sweep", "--step-length", "0.40", "0.45", "--alpha-deg", "0", "20", "--mode", "normal", "anti-normal",
               "--out", str(out), "--workers", "2")
    assert proc.returncode == 0, proc.stderr
    assert f"8 gaits (8 converged, 8 admissible) written to {out}/sweep.csv" in proc.stdout
    rows = list(csv.DictReader((out / "sweep.csv").open()))
    assert len(rows) == 8 and {r["mode"] for r in rows} == {"normal", "anti-normal"}
    assert json.loads((out / "sweep.json").read_text())["complete"] is True
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == ["W_vs_alpha_L0.400_T0.450.png", "W_vs_alpha_L0.450_T0.450.png"]
    assert all((out / p).read_bytes()[:8] == PNG_SIGNATURE for p in pngs)


@pytest.mark.parametrize(
    "args, message",
    [
        (["sweep", "--alpha-deg-range", "45", "0", "1.5"], "arm amplitude range is inverted: stop 0 is below start 45"),
        (["sweep", "--step-length-range", "0.4", "0.5", "0"], "step length range step must be positive, got 0"),
        (["sweep", "--alpha-deg"], "argument --alpha-deg: expected at least one argument"),
        (["sweep", "--mode"], "argument --mode: expected at least one argument"),
        (["sweep", "--alpha-deg-range", "0", "45", "0.01"],
         "the sweep has 4501 cases (more than 2000): confirm to run it (--yes)"),
        (["sweep", "--mode", "normal", "sideways"], "argument --mode: invalid choice: 'sideways'"),
        (["sweep", "--period", "0"], "period must be positive"),
        (["sweep", "--workers", "0"], "the number of workers must be at least 1, got 0"),
        (["sweep", "--step-length", "0.45", "--step-length-range", "0.4", "0.5", "0.05"], "not allowed with argument"),
        (["optimize-arms", "--alpha-deg-range", "30", "10", "1.5"], "arm amplitude range is empty or inverted: [30, 10] deg"),
        (["optimize-arms", "--alpha-deg-range", "0", "45", "0"], "arm amplitude range step must be positive, got 0"),
        (["optimize-arms", "--friction-margin", "0.6"], "friction margin must be in [0, 0.5)"),
        (["plan", "--friction", "-0.5"], "friction coefficient must be positive (or inf), got -0.5"),
        (["plan", "--min-clearance", "-0.001"], "swing clearance margin must be 0 (none) or positive"),
        (["optimize-arms", "--mode", "hop"], "argument --mode: invalid choice: 'hop'"),
        (["figure", "fig6"], "argument name: invalid choice: 'fig6'"),
        (["plan", "--step-length", "abc"], "argument --step-length: invalid float value: 'abc'"),
        (["results-page", "--map-stride", "0"], "--map-stride: must be 1 or more, got 0"),
    ],
)
def test_bad_input_is_one_line_and_status_2(tmp_path, args, message):
    out = tmp_path / "never"
    proc = run(*args, *(["--out", str(out)] if args[0] == "sweep" else []))
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert lines[0].startswith("biped-gait")
    assert proc.stdout == "" and not out.exists()


def _sigint_as_in_a_terminal() -> None:
    """In the child before exec: SIGINT at its default, as for a terminal's foreground job (a
    test session started in the background, ``cmd &`` or ``nohup``, ignores SIGINT, and Python
    keeps an inherited SIG_IGN: Ctrl-C would never reach the sweep)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def test_interrupted_sweep_keeps_what_it_computed(tmp_path):
    """Ctrl-C reaches the whole process group (the command and its workers), as in a terminal."""
    out = tmp_path / "out"
    args = ["sweep", "--step-length-range", "0.30", "0.56", "0.02", "--alpha-deg-range", "0", "45", "2.5",
            "--mode", "normal", "anti-normal", "--out", str(out), "--workers", "2"]
    proc = subprocess.Popen([ENTRY, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, preexec_fn=_sigint_as_in_a_terminal)
    try:
        deadline = time.monotonic() + 200  # the first chain of gaits (3 s here), on a busy machine too
        written = False
        while time.monotonic() < deadline and proc.poll() is None and not written:
            written = (out / "sweep.csv").exists() and len((out / "sweep.csv").read_text().splitlines()) > 1
            time.sleep(0.05)
        assert proc.poll() is None, "the sweep ended before it could be interrupted"
        os.killpg(proc.pid, signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert written, f"no chain of gaits written within 200 s: {stderr}"
    assert proc.returncode == 130, stderr
    match = re.search(r"interrupted: (\d+) of 532 gaits kept in", stderr)
    assert match, stderr
    kept = int(match.group(1))
    assert 0 < kept < 532 and kept % 19 == 0  # whole chains of 19 amplitudes
    rows = list(csv.DictReader((out / "sweep.csv").open()))
    document = json.loads((out / "sweep.json").read_text())
    assert len(rows) == kept == document["cases_written"] == len(document["cases"])
    assert document["complete"] is False and document["cases_planned"] == 532
    assert stdout == ""


def test_optimize_arms_reports_an_interior_optimum():
    proc = run("optimize-arms", "--alpha-deg-range", "0", "45", "5")
    assert proc.returncode == 0, proc.stderr
    assert re.match(r"optimal arm amplitude alpha\* = 2\d\.\d{3} deg \(normal gait, L = 0.45 m, T = 0.45 s, "
                    r"params aoustin2013\): W = \d+\.\d{4} N m s", proc.stdout), proc.stdout
    assert "an interior minimum of W on [0, 45] deg" in proc.stdout


def test_optimize_arms_says_when_there_is_no_interior_minimum():
    proc = run("optimize-arms", "--params", "aoustin2013-table", "--alpha-deg-range", "0", "45", "5")
    assert proc.returncode == 0, proc.stderr
    assert "W(alpha) has no interior minimum on [0, 45] deg" in proc.stdout
    assert "end point alpha = 0.000 deg" in proc.stdout and "This is not an optimum." in proc.stdout


def test_optimize_arms_without_any_admissible_gait_exits_1():
    proc = run("optimize-arms", "--period", "1.5", "--alpha-deg-range", "0", "45", "45")
    assert proc.returncode == 1
    assert proc.stderr.startswith("biped-gait: no admissible normal gait at L = 0.45 m, T = 1.5 s")


@pytest.mark.parametrize("name, options", [("fig4", ["--alpha-deg-range", "0", "45", "7.5"]),
                                           ("fig5", ["--alpha-deg-range", "0", "45", "5"])])
def test_figure_commands_write_png(tmp_path, name, options):
    out = tmp_path / "docs" / f"{name}.png"
    proc = run("figure", name, "--out", str(out), "--workers", "2", *options)
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes()[:8] == PNG_SIGNATURE
    assert f"{name} written to {out}" in proc.stdout
    assert proc.stdout.count("optimal arm amplitude alpha*") == (3 if name == "fig4" else 1)


@pytest.mark.timeout(300)
def test_results_page_is_generated_with_its_figures(tmp_path):
    """Every section and figure of the page, on coarse spacings (the arm amplitudes; the walk's
    closed loops and pushes at alpha 0 only, and alpha*; the maps' optima on one atlas node in 8
    along L and T: 3 on each set's atlas, 10 and 6 in 4; the boundary's 17 bisections alike) and a
    part of the pulses and push directions (the left alone: the sides' comparison, which needs both,
    is test_walking_page's; docs/results.md is made with the finer defaults); the
    lasting double support's and the actuated swing's sections from their stored studies, copied
    beside the page."""
    page = tmp_path / "docs" / "results.md"
    page.parent.mkdir()
    shutil.copy(LASTING_STUDY, page.parent)
    shutil.copy(ACTUATED_STUDY, page.parent)
    proc = run("results-page", "--out", str(page), "--alpha-step", "7.5", "--walk-alpha-step", "90", "--workers", "2",
               "--pulse-durations", "5", "--push-directions", "left", "--map-stride", "8", timeout=280)
    assert proc.returncode == 0, proc.stderr
    text = page.read_text()
    for heading in ("## Parameter set `aoustin2013` (default)", "## Parameter set `aoustin2013-table`",
                    "## The paper's claims, checked on these numbers",
                    "## Where the project and the paper differ, and why",
                    "## Where walking is possible (maps beyond the paper)", "## Stability of the gaits (beyond the paper)",
                    "## The physics a reviewer would check (beyond the paper)", "### Beside human walking",
                    "## The walk: stability, pushes, commanded speed", "## Walking on circles (beyond the paper)",
                    "## A double support that lasts, walked in MuJoCo (beyond the paper)",
                    "## A double support that lasts: its effort and the arms' optimum (beyond the paper)"):
        assert heading in text
    check_lasting_section(text, json.loads(LASTING_STUDY.read_text()))
    check_actuated_section(text, json.loads(ACTUATED_STUDY.read_text()))
    links = re.findall(r"!\[[^]]*\]\(([^)]+)\)", text)
    assert links[:3] == ["fig4.png", "fig5.png", "fig4-aoustin2013-table.png"]
    assert {"map-region-aoustin2013.png", "map-optimum-aoustin2013-table.png", "stability.png",
            "rate-bound.png", "lasting-effort.png", "lasting-arms.png", "actuated-effort.png"} <= set(links)
    assert all((page.parent / link).read_bytes()[:8] == PNG_SIGNATURE for link in links)
    assert "| 0.45 | 0.45 | " in text and "| 23.50 | " in text and "| 101.90 |" in text  # the paper's numbers beside
    assert "| 0.45 | 0.50 | " in text and "T+ about the new stance foot | normal | 7.65 |" in text
    assert "no interior minimum for any L" in text  # the table inertia, from computed numbers
    assert "from optimizations on one atlas node in 8 along L and T, these maps" in text
    assert "by differences of the walker's step, L = 0.40, 0.45, 0.50 m, alpha 0 deg" in text
    assert "| 5 | 20 | " in text and "The largest d tried that walks 20 steps: 5 ms." in text  # MuJoCo, 5 ms pulses
    assert "| forward | - | - | - |" in text and "| right | - | - | - |" in text  # the left only
    assert re.search(r"\| left \| [0-9.]+ \| [0-9.]+ \| [0-9.]+ \|", text) and "larger pushes" not in text


@pytest.mark.parametrize("options, alpha, effort", [
    ([], 23.66, 32.78),  # the friction cone of the parameter set, mu = 0.5
    (["--friction", "inf"], 27.04, 31.24),  # no cone: the paper's LP
    (["--effort-coordinates", "absolute"], 19.53, 59.72),  # the absolute reading, with the cone
    (["--effort-coordinates", "absolute", "--friction", "inf"], 23.89, 56.31),  # the absolute reading, no cone
])
def test_optimize_arms_reproduces_the_results_pages_optima(options, alpha, effort):
    """The rows of docs/results.md's table at L = T = 0.45 (two decimals there), from the CLI."""
    proc = run("optimize-arms", *options, "--json", "-")
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout)
    assert result["interior"] and result["where"] == "interior minimum"
    assert result["alpha_deg"] == pytest.approx(alpha, abs=0.006) and result["W"] == pytest.approx(effort, abs=0.006)
    assert result["gait"]["friction"] == (None if "inf" in options else 0.5)  # inf is null in JSON
    assert "optimal arm amplitude alpha*" in proc.stderr  # the text goes to stderr with --json -


def test_every_gait_verb_writes_its_json(tmp_path):
    out = tmp_path / "plan"
    proc = run("plan", "--min-clearance", "0.005", "--out", str(out), "--json", str(tmp_path / "plan.json"))
    assert proc.returncode == 1, proc.stderr  # it meets the limits, not the margin
    assert "not admissible: meets the limits but not the margins: swing clearance" in proc.stdout
    document = json.loads((tmp_path / "plan.json").read_text())
    assert document == json.loads((out / "plan.json").read_text())
    assert document["within_limits"] is True and document["admissible"] is False and document["min_clearance"] == 0.005
    assert (out / "plan.png").read_bytes()[:8] == PNG_SIGNATURE
    figure = run("figure", "fig5", "--alpha-deg-range", "0", "45", "5", "--out", str(tmp_path / "fig5.png"),
                 "--workers", "1", "--json", "-")
    assert figure.returncode == 0, figure.stderr
    momentum = json.loads(figure.stdout)["momentum"]
    assert set(momentum) == {"normal", "anti-normal"} and len(momentum["normal"]["t"]) == len(momentum["normal"]["h_vertical"])
