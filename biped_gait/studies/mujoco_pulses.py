"""The double support's duration d walked in MuJoCo (docs/results.md, "A double support that
lasts"): for each d, a walk of a gait with ``engine="mujoco"`` (core/walking/engines/mujoco.py,
phases/pulses.py) and momentum steering, and what it takes:

- the effort E = (d / 2) sum |u| of the last double support (N m s) beside the impulses' W there;
- the friction it needs: the largest |F_xy| / F_z of the planned pulses (the planner's model, at
  the pulses' nodes) and of MuJoCo's stance-tip reaction over the walk's samples;
- the largest pulse torque (N m);
- where the walk settles: the last step's duration (s), and its touchdown's distance from the
  plan's (max over q and qd of the predicted ballistic touchdown, rad, rad/s);
- the closed loop's stability: a shove of ``SHOVE`` rad/s on every joint at the start of step
  ``SHOVE_AT``, and the contraction per step of its effect on the touchdowns after it (the
  geometric mean of the ratio of successive differences from the unshoved walk);
- how many steps it walked, and why it stopped short.

Run: ``.venv/bin/python -m biped_gait.studies.mujoco_pulses [d_ms ...]`` (a Markdown table).
"""

from __future__ import annotations

import math
import sys
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np

from ..core.gait.planner import GaitRequest
from ..core.model.params import load_params
from ..core.walking.steering import DEFAULT_RATE
from ..core.walking.events import Fell, Finished, StepSamples, Touchdown
from ..core.walking.orbit import PlannedOrbit
from ..core.walking.runner import Walker
from ..core.walking.walk import Walk
from .executors import planner_for

STEPS = 20
SHOVE_AT = 10  # step
SHOVE = 1e-4  # rad/s on every joint
DURATIONS = (1e-3, 2e-3, 5e-3, 1e-2, 2e-2, 5e-2)  # s


@dataclass(frozen=True)
class PulseRow:
    """One duration's walk (module docstring; units SI, rad)."""

    duration: float
    steps: int
    reason: str
    effort: float
    impulsive_effort: float
    friction_planned: float
    friction_used: float
    peak_torque: float
    period: float
    state_error: float
    contraction: float

    def markdown(self) -> str:
        """The row of ``table``."""
        if self.steps < STEPS:
            return f"| {self.duration * 1e3:g} | {self.steps} ({self.reason}) | | | | | | | |"
        return (f"| {self.duration * 1e3:g} | {self.steps} | {self.effort:.2f} ({self.impulsive_effort:.2f}) | "
                f"{self.friction_planned:.3f} | {self.friction_used:.3f} | {self.peak_torque:.0f} | {self.period:.4f} | "
                f"{self.state_error:.3f} | {self.contraction:.2f} |")


HEADER = ("| d (ms) | steps walked | E (W) per step, N m s | friction planned | friction in MuJoCo | "
          "peak torque, N m | step duration, s | touchdown off the plan | contraction per step |\n"
          "|---|---|---|---|---|---|---|---|---|")


@dataclass(frozen=True)
class _Walked:
    """A walk's double supports (``PulsedTouchdown``), how it ended, and the largest |F_xy| / F_z of
    MuJoCo's stance-tip reaction over its samples."""

    records: list
    end: object
    friction_used: float


def _walk(orbit: PlannedOrbit, duration: float, shove: bool) -> _Walked:
    def before(walker: Walker) -> None:
        if shove and walker.state.step == SHOVE_AT:
            walker.shove(np.full(len(walker.state.qd), SHOVE))

    walk = Walk(orbit, 100.0, STEPS, engine="mujoco", pulse_duration=duration, momentum_rate=DEFAULT_RATE,
                before_step=before)
    records, end, used = [], None, 0.0
    for item in walk.batches():
        if isinstance(item, StepSamples):
            grf = np.array([sample.grf for sample in item.samples])
            loaded = grf[:, 2] > 0
            if loaded.any():
                used = max(used, float(np.max(np.hypot(grf[loaded, 0], grf[loaded, 1]) / grf[loaded, 2])))
        elif isinstance(item, Touchdown):
            records.append(item.double_support)
        elif isinstance(item, (Fell, Finished)):
            end = item
    return _Walked(records, end, used)


def pulse_row(orbit: PlannedOrbit, duration: float) -> PulseRow:
    """The walk of ``orbit`` with a double support of ``duration`` s, and its shoved twin."""
    walked = _walk(orbit, duration, shove=False)
    records, end = walked.records, walked.end
    if isinstance(end, Fell) or not records:
        reason = end.reason if isinstance(end, Fell) else "no touchdown"
        return PulseRow(duration, len(records), reason, *([math.nan] * 8))
    shoved = _walk(orbit, duration, shove=True)
    states = [np.concatenate([r.q_predicted, r.qd_predicted]) for r in records]
    twins = [np.concatenate([r.q_predicted, r.qd_predicted]) for r in shoved.records]
    gaps = [float(np.max(np.abs(a - b))) for a, b in zip(states[SHOVE_AT:], twins[SHOVE_AT:])]
    contraction = (gaps[-1] / gaps[0]) ** (1.0 / (len(gaps) - 1)) if len(gaps) > 1 and gaps[0] > 0 else math.nan
    last = records[-1]
    error = orbit.touchdown_error(last.q_predicted, last.qd_predicted)
    return PulseRow(duration, len(records), "", last.effort, last.impulsive_effort,
                    max(r.friction_planned for r in records), walked.friction_used,
                    max(r.peak_torque for r in records), records[-1].t - records[-2].t if len(records) > 1 else last.t,
                    error, contraction)


DEFAULT_REQUEST = GaitRequest(0.45, 0.45, math.radians(23.5), "normal")


def pulse_row_of(duration: float, request: GaitRequest = DEFAULT_REQUEST) -> PulseRow:
    """``pulse_row`` of the gait of ``request``, planned by this worker's planner (``planner_for``)."""
    return pulse_row(PlannedOrbit.of(planner_for(load_params(request.params)).plan(request)), duration)


def pulse_rows(executor: Executor, durations: tuple[float, ...] = DURATIONS,
               request: GaitRequest = DEFAULT_REQUEST) -> list[PulseRow]:
    """``pulse_row_of`` for each of ``durations`` (s), one task each on ``executor``."""
    return [task.result() for task in [executor.submit(pulse_row_of, d, request) for d in durations]]


def pulse_lines(rows: list[PulseRow]) -> list[str]:
    """The results page's table of ``rows`` and its reading (the largest d walked)."""
    walked = [row.duration for row in rows if row.steps >= STEPS]
    largest = (f"The largest d tried that walks {STEPS} steps: {max(walked) * 1e3:g} ms." if walked
               else f"None of the durations tried walks {STEPS} steps.")
    return [HEADER, *(row.markdown() for row in rows), "", largest]


def table(durations: tuple[float, ...] = DURATIONS, request: GaitRequest = DEFAULT_REQUEST) -> str:
    """The results page's table and reading (``pulse_lines``) for each of ``durations`` (s), in
    this process."""
    return "\n".join(pulse_lines([pulse_row_of(d, request) for d in durations]))


if __name__ == "__main__":
    print(table(tuple(float(x) * 1e-3 for x in sys.argv[1:]) or DURATIONS))
