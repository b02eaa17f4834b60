"""The push study and the results page's section on the walk, on a small scale: the command's
files and its one-line errors, the limits bracketed by their trials, the closed loops, the speed
ramp, the figures and the section's text."""

from __future__ import annotations

import csv
import json
import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
import pytest

from biped_gait.cli import main as cli_main
from biped_gait.core.model.params import load_params
from biped_gait.core.gait.planner import GaitRequest
from biped_gait.core.walking.steering import DEFAULT_RATE
from biped_gait.studies.figures import save
from biped_gait.studies.push_study import MAX_IMPULSE, PushedGait, run_push_study
from biped_gait.studies.walking_page import Walking, closed_loop_radius, speed_ramp, walking_figures, walking_section

pytestmark = pytest.mark.studies


def test_the_push_study_command_writes_its_files(tmp_path):
    out = tmp_path / "push"
    assert cli_main(["push-study", "--alpha-deg", "23.5", "--directions", "backward", "--workers", "1",
                     "--out", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == {"push.csv", "push.json", "push-polar.png"}
    [row] = list(csv.DictReader(open(out / "push.csv")))
    assert row["direction"] == "backward" and float(row["alpha_deg"]) == pytest.approx(23.5)
    [limit] = json.loads((out / "push.json").read_text())["limits"]
    recovered = [t["magnitude"] for t in limit["trials"] if t["recovered"]]
    failed = [t["magnitude"] for t in limit["trials"] if not t["recovered"]]
    assert 0 < limit["limit"] == max(recovered) < limit["first_failure"] == min(failed) < MAX_IMPULSE
    assert limit["first_failure"] - limit["limit"] <= 0.02 * limit["first_failure"] + 1e-12


@pytest.mark.parametrize("args, message", [
    (["--phase", "1.5"], "--phase must be in [0, 1)"),
    (["--directions", "up"], "argument --directions: invalid choice: 'up'"),
    (["--momentum-rate", "1.0"], "--momentum-rate must be below 1"),
])
def test_the_push_study_refuses_bad_input_in_one_line(tmp_path, capsys, args, message):
    assert cli_main(["push-study", "--out", str(tmp_path / "p"), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_the_walking_section_and_its_figures(default_gait, planner, tmp_path):
    params = load_params()
    alpha = default_gait.arm_amplitude
    other = planner.plan(GaitRequest(0.40, 0.45, alpha, default_gait.mode))
    loops = [closed_loop_radius(params, length, 0.45, alpha, steering)
             for length in (0.40, 0.45) for steering in (None, DEFAULT_RATE)]
    by_rate = {lp.steering: lp.radius for lp in loops if lp.step_length == 0.45}
    assert 0.98 < by_rate[None] < 1.0 and by_rate[DEFAULT_RATE] == pytest.approx(DEFAULT_RATE, abs=5e-3)
    with ThreadPoolExecutor(2) as executor:
        pushed = PushedGait(params, 0.45, 0.45, "normal")
        pushes = run_push_study(executor, pushed, [(0.0, "left"), (alpha, "left"), (alpha, "right")])
        plain = run_push_study(executor, replace(pushed, steering=None), [(alpha, "left")])
    assert plain[0].limit < pushes[1].limit
    ramp, rule, note = speed_ramp(params, alpha, (0.9, 1.0), hold=3)
    print(f"\n{rule}; {note}; speeds " + " ".join(f"{s.measured:.3f}" for s in ramp))
    assert ramp[0].commanded == 0.9 and ramp[-1].commanded == 0.9
    assert ramp[-1].measured == pytest.approx(0.9, rel=0.02) and max(s.aimed for s in ramp) == pytest.approx(1.0)
    walking = Walking([default_gait, other], loops, pushes, plain, alpha, ramp, rule, note)
    figures = walking_figures(walking, "aoustin2013")
    paths = {caption: save(fig, tmp_path / name).name for caption, (fig, name) in figures.items()}
    assert all((tmp_path / name).stat().st_size > 10_000 for name in paths.values())
    text = "\n".join(walking_section(walking, paths))
    assert "## The walk: stability, pushes, commanded speed" in text
    assert f"by differences of the walker's step, L = 0.40, 0.45 m, alpha {math.degrees(alpha):g} deg)" in text
    assert f"| left | {pushes[0].limit:.3g} | {pushes[1].limit:.3g} | {plain[0].limit:.3g} |" in text
    left, right = pushes[1].limit, pushes[2].limit  # at alpha: the side taking the larger push said, both figures
    side = "to the left, towards the swing foot's side," if left > right else "to the right, over the stance foot,"
    assert f"The walker takes larger pushes {side} than to the " in text
    assert f"({left:.3g} against {right:.3g} N s at alpha*)" in text
    assert all(f"]({name})" in text for name in paths.values())
    assert np.isfinite([s.W for s in ramp]).all() and len(ramp) >= 9
