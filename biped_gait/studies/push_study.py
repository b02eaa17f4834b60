"""The push-recovery study: the largest push on the trunk the walker recovers from, per
direction and arm amplitude (docs/model.md section 8.6), in parallel on an executor.

A trial walks the gait (L, T, alpha, mode) from its orbit with the simulator's walker (re-aim
with momentum steering, samples at ``RATE``), pushes the trunk with a horizontal impulse P
(N s, world axes) at ``phase`` T of the first step (the right foot in stance), and counts as
**recovered** if the robot does not fall and, ``RECOVERY_STEPS`` steps after the pushed one,
its state at the step's start is within ``RECOVERY_TOLERANCE`` (rad, rad/s, max-norm) of the
orbit's start (q0, qd_a).

The largest push per direction: magnitudes from ``SCAN_START`` up by the factor ``SCAN_FACTOR``
until the first push not recovered, then bisection between it and the last recovered one to
``BISECTION_TOLERANCE`` (relative). The set of recovered magnitudes need not be an interval (the
re-aim's boundary-value problem has folds: a push may fail where a larger one is recovered), so
the figure is the largest push below which every push tried was recovered, and the first
failure found above it is reported with its reason.
"""

from __future__ import annotations

import csv
import json
import math
import sys
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..core.dynamics.hybrid import HybridStep
from ..core.model.params import BipedParams
from ..core.gait.planner import GaitRequest
from ..core.walking.push import DIRECTIONS, Push, horizontal_impulse
from ..core.walking.steering import DEFAULT_RATE
from ..core.walking.orbit import PlannedOrbit
from ..core.walking.runner import Walker
from .executors import planner_for

if TYPE_CHECKING:  # matplotlib and tqdm are imported where they are used: the CLI reads this module's defaults
    from matplotlib.figure import Figure

RECOVERY_STEPS = 10
RECOVERY_TOLERANCE = 1e-3  # rad, rad/s
RATE = 500.0  # Hz: samples per second, as the simulator's default (falls are found at samples)
SCAN_START = 0.05  # N s
SCAN_FACTOR = 1.5
MAX_IMPULSE = 50.0  # N s: the scan stops there
BISECTION_TOLERANCE = 0.02  # relative width of the final bracket
PHASE = 0.5  # the default: mid-step
STUDY_DIRECTIONS = {"forward": DIRECTIONS["forward"], "forward-left": math.pi / 4, "left": DIRECTIONS["left"],
                    "backward-left": 3 * math.pi / 4, "backward": DIRECTIONS["backward"], "backward-right": -3 * math.pi / 4,
                    "right": DIRECTIONS["right"], "forward-right": -math.pi / 4}
"""The directions of the study (rad from +x towards +y): the named ones of ``push`` and the diagonals."""


@dataclass(frozen=True)
class PushTrial:
    """One push of ``magnitude`` (N s): recovered or not, and what happened (the fall with its
    step and time, or the distance to the orbit after the recovery steps, rad / rad/s)."""

    magnitude: float
    recovered: bool
    outcome: str
    distance: float


@dataclass(frozen=True)
class PushLimit:
    """The largest push recovered (``limit``, N s; 0 if the smallest tried fails) in
    ``direction`` (name; ``angle`` rad from +x towards +y) at arm amplitude ``alpha`` (rad) and
    ``phase`` (fraction of T), with the first failure above it (N s, inf if none up to
    ``MAX_IMPULSE``) and every trial; ``steering``: the momentum steering rate (None: the
    duration-only re-aim)."""

    direction: str
    angle: float
    alpha: float
    phase: float
    steering: float | None
    limit: float
    first_failure: float
    failure: str
    trials: tuple[PushTrial, ...]


def push_trial(hybrid: HybridStep, orbit: PlannedOrbit, magnitude: float, angle: float, phase: float,
               steering: float | None = DEFAULT_RATE) -> PushTrial:
    """Walk ``orbit`` and push the trunk with ``magnitude`` (N s) in the horizontal direction
    ``angle`` (rad) at ``phase`` T of the first step; recovered or not (module docstring)."""
    walker = Walker(hybrid, orbit, rate=RATE, momentum_rate=steering)
    walker.push(Push(horizontal_impulse(magnitude, angle), phase * orbit.period))
    start = np.concatenate([orbit.q0, orbit.qd_a])
    for _ in range(RECOVERY_STEPS + 1):
        step = walker.state.step
        outcome = walker.walk_step()
        if outcome.touchdown is None:
            t = outcome.samples[-1].t if outcome.samples else walker.state.t
            return PushTrial(magnitude, False, f"fell in step {step} at t = {t:.3f} s: {outcome.fall}", math.nan)
    distance = float(np.max(np.abs(np.concatenate([walker.state.q, walker.state.qd]) - start)))
    recovered = distance < RECOVERY_TOLERANCE
    text = "recovered" if recovered else f"not back on the orbit after {RECOVERY_STEPS} steps"
    return PushTrial(magnitude, recovered, f"{text} (distance {distance:.1e})", distance)


def largest_push(hybrid: HybridStep, orbit: PlannedOrbit, direction: str, angle: float, phase: float = PHASE,
                 steering: float | None = DEFAULT_RATE) -> PushLimit:
    """The largest push recovered in ``direction`` (scan, then bisection; module docstring)."""
    trials = []

    def trial(magnitude: float) -> PushTrial:
        trials.append(push_trial(hybrid, orbit, magnitude, angle, phase, steering))
        return trials[-1]

    low, high, failed = 0.0, SCAN_START, None
    while high <= MAX_IMPULSE:
        result = trial(high)
        if not result.recovered:
            failed = result
            break
        low, high = high, high * SCAN_FACTOR
    while failed is not None and high - low > BISECTION_TOLERANCE * high:
        middle = 0.5 * (low + high)
        result = trial(middle)
        if result.recovered:
            low = middle
        else:
            high, failed = middle, result
    return PushLimit(direction, angle, orbit.arm_amplitude, phase, steering, low,
                     failed.magnitude if failed else math.inf, failed.outcome if failed else "", tuple(trials))


@dataclass(frozen=True)
class PushedGait:
    """What a push study pushes, and how: the gait of the parameter set ``params`` at L (m), T (s)
    and ``mode`` (each case gives its alpha and direction), with further ``GaitRequest`` fields
    ``options``; pushed at ``phase`` T of the first step, walked with the momentum steering rate
    ``steering`` (None: the plain re-aim)."""

    params: BipedParams
    step_length: float
    period: float
    mode: str
    phase: float = PHASE
    steering: float | None = DEFAULT_RATE
    options: Mapping[str, object] = field(default_factory=dict)


def push_task(pushed: PushedGait, alpha: float, direction: str) -> PushLimit:
    """Worker entry: plan the gait of ``pushed`` at ``alpha`` (rad) with this worker's planner,
    then ``largest_push`` in ``direction`` (a name of ``STUDY_DIRECTIONS``)."""
    planner = planner_for(pushed.params)
    step_length, period, mode = pushed.step_length, pushed.period, pushed.mode
    gait = planner.plan(GaitRequest(step_length, period, alpha, mode, **pushed.options))
    if not gait.admissible:
        raise ValueError(f"the gait L = {step_length:g} m, T = {period:g} s, alpha = {math.degrees(alpha):.2f} deg "
                         f"({mode}) is not admissible: {'; '.join(gait.reasons)}")
    return largest_push(planner.hybrid, PlannedOrbit.of(gait), direction, STUDY_DIRECTIONS[direction], pushed.phase,
                        pushed.steering)


def run_push_study(executor: Executor, pushed: PushedGait, cases: Sequence[tuple[float, str]]) -> list[PushLimit]:
    """``largest_push`` of ``pushed`` for each (alpha rad, direction name) of ``cases``, all at
    once on ``executor``, with a progress bar on stderr; in the order of ``cases``."""
    from tqdm import tqdm

    futures = {executor.submit(push_task, pushed, alpha, direction): k for k, (alpha, direction) in enumerate(cases)}
    results: list[PushLimit | None] = [None] * len(cases)
    with tqdm(total=len(futures), unit="direction", desc="push study", file=sys.stderr) as bar:
        for future in as_completed(futures):
            results[futures[future]] = future.result()
            bar.update()
    return results


def study_cases(alphas: Sequence[float], directions: Sequence[str]) -> list[tuple[float, str]]:
    """Every (alpha, direction); ``ValueError`` for an unknown direction name."""
    unknown = [d for d in directions if d not in STUDY_DIRECTIONS]
    if unknown:
        raise ValueError(f"unknown push direction {unknown[0]!r}: use {', '.join(STUDY_DIRECTIONS)}")
    return [(alpha, direction) for alpha in alphas for direction in directions]


# Output --------------------------------------------------------------------------------------

def limit_record(limit: PushLimit) -> dict:
    """A limit as JSON-ready values (angles also in degrees; inf as null)."""
    record = asdict(limit)
    record["alpha_deg"] = round(math.degrees(limit.alpha), 9)
    record["angle_deg"] = round(math.degrees(limit.angle), 9)
    record["first_failure"] = limit.first_failure if math.isfinite(limit.first_failure) else None
    record["trials"] = [{**asdict(t), "distance": t.distance if math.isfinite(t.distance) else None} for t in limit.trials]
    return record


def document(limits: Sequence[PushLimit]) -> dict:
    """The study as JSON-ready values (``push.json``): the recovery criterion and every limit
    with its trials."""
    return {"recovery_steps": RECOVERY_STEPS, "recovery_tolerance": RECOVERY_TOLERANCE,
            "limits": [limit_record(limit) for limit in limits]}


def write_results(limits: Sequence[PushLimit], out: Path) -> list[Path]:
    """``push.csv`` (one row a direction and alpha) and ``push.json`` (with every trial) in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    records = [limit_record(limit) for limit in limits]
    columns = ["direction", "angle_deg", "alpha_deg", "phase", "steering", "limit", "first_failure", "failure"]
    with open(out / "push.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        writer.writerows({c: r[c] for c in columns} for r in records)
    (out / "push.json").write_text(json.dumps(document(limits), indent=1))
    return [out / "push.csv", out / "push.json"]


def _figure(polar: bool = False) -> tuple[Figure, object]:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 5.2), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.add_subplot(projection="polar" if polar else None)


CURVE_GAP = math.radians(45.0)
"""rad: the polar plot joins its directions by a curve only where none is farther than this from the
next (8 or more directions around); fewer are markers alone, as a curve between them would claim
limits that were not measured."""


def polar_figure(limits: Sequence[PushLimit], title: str) -> Figure:
    """The largest push recovered (N s, the radius) against its direction, one set of markers per
    alpha, a closed curve through them where the directions are close enough (``CURVE_GAP``)
    (world axes: forward up, left to the left, as seen from above), the pushed step's stance foot
    (the right: the walk's first step) named at its side; the radial labels, with their unit, in
    the widest gap between the measured directions."""
    from matplotlib.ticker import FuncFormatter

    fig, ax = _figure(polar=True)
    ax.set_theta_zero_location("N")  # forward up; angles counter-clockwise: left to the left
    for i, alpha in enumerate(sorted({limit.alpha for limit in limits})):
        curve = sorted((limit for limit in limits if limit.alpha == alpha), key=lambda limit: limit.angle % (2 * math.pi))
        angles = [limit.angle % (2 * math.pi) for limit in curve]
        values = [limit.limit for limit in curve]
        gaps = np.diff([*angles, angles[0] + 2 * math.pi])
        closed = len(angles) >= 3 and float(np.max(gaps)) <= CURVE_GAP + 1e-9
        ax.plot(angles + angles[:1] if closed else angles, values + values[:1] if closed else values,
                "o-" if closed else "o", color=f"C{i}", markersize=5, label=f"alpha = {math.degrees(alpha):.1f} deg")
    ax.set_xticks(np.radians([0, 45, 90, 135, 180, 225, 270, 315]),
                  ["forward", "", "left", "", "backward", "", "right:\nstance\nfoot", ""])
    measured = sorted({limit.angle % (2 * math.pi) for limit in limits})
    gaps = np.diff([*measured, measured[0] + 2 * math.pi])
    widest = int(np.argmax(gaps))
    ax.set_rlabel_position(math.degrees(measured[widest] + gaps[widest] / 2))  # off the data
    ax.yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g} N s"))
    ax.set_title(f"{title}\nright foot in stance; radius: the largest push recovered (N s)", fontsize="medium", pad=18)
    ax.legend(fontsize="small", loc="lower left", bbox_to_anchor=(-0.15, -0.12))
    return fig


def limit_vs_alpha_figure(limits: Sequence[PushLimit], title: str) -> Figure:
    """The largest push recovered (N s) against alpha (deg), one curve per direction."""
    fig, ax = _figure()
    for i, direction in enumerate(dict.fromkeys(limit.direction for limit in limits)):
        curve = sorted((limit for limit in limits if limit.direction == direction), key=lambda limit: limit.alpha)
        ax.plot([math.degrees(limit.alpha) for limit in curve], [limit.limit for limit in curve], "o-", color=f"C{i}",
                markersize=4, label=direction)
    ax.set_xlabel("arm amplitude alpha (deg)")
    ax.set_ylabel("largest push recovered (N s)")
    ax.set_yscale("log")
    plain_log_axis(ax.yaxis)
    ax.set_title(title, fontsize="medium")
    ax.grid(True, alpha=0.3, which="both")
    ax.legend(fontsize="small")
    return fig


def plain_log_axis(axis) -> None:
    """A log axis labelled as numbers (0.5, 1, 2, 3), not powers of ten (4 x 10^-1): ticks at
    1, 2, 3 and 5 of each decade."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 3.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())


def describe(limit: PushLimit) -> str:
    """One line: the limit, its direction and alpha, and the first failure above it."""
    above = (f"first failure {limit.first_failure:.3f} N s: {limit.failure}" if math.isfinite(limit.first_failure)
             else f"no failure up to {MAX_IMPULSE:g} N s")
    return (f"{limit.direction:>14s}, alpha = {math.degrees(limit.alpha):5.2f} deg: largest push recovered "
            f"{limit.limit:.3f} N s ({above})")

