"""Reference figures of the 9-DOF parameter sets, and how precisely each one is known.

What is stored (``tests/data/reference/``): the plan JSON (every figure and the sampled
trajectory, less the wall time of the solve) of five gaits per set, chosen to exercise each
option (modes, closures, efforts, friction, rate bound, the effort's reading); one 20-step walk of
the default gait with momentum steering (every sample's instant, step, state, ground reaction and
pelvis pose, every touchdown's impulses); a sweep's CSV; and a SHA-256 of every node array of the
shipped atlases.

``tests/test_reference_figures.py`` compares what this machine computes with them, each figure
within the tolerance ``TOLERANCES`` writes beside it, never bit for bit: another CPU's BLAS, Eigen
or compiler path moves the last digits (on a 2-core AMD EPYC, W moved by 3e-14 relative and the
smallest Floquet multipliers by 5e-4 relative, at 1e-8 of the largest). It also proves that no
comparison depends on bits: the same references hold for requests moved by a few ulps. The
shipped atlases are checked by solving some of their nodes again (their stored hashes are a
developer's tool).

A developer's tool, outside the suite, checks a refactor meant to change nothing bit for bit
and regenerates the references when the figures are meant to change:

    .venv/bin/python tools/reference_figures.py --bits
    .venv/bin/python tools/reference_figures.py --store
"""

from __future__ import annotations

import csv
import gzip
import hashlib
import io
import json
import math
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

DATA = Path(__file__).resolve().parent / "data" / "reference"
SETS = ("aoustin2013", "aoustin2013-table")
# (L m, T s, alpha deg, mode, extra request fields)
REQUESTS = (
    (0.45, 0.45, 23.5, "normal", {}),
    (0.40, 0.45, 21.1, "anti-normal", {}),
    (0.50, 0.50, 30.0, "normal", {"closure": "slack"}),
    (0.45, 0.45, 10.0, "normal", {"effort": "l2"}),
    (0.55, 0.48, 15.0, "normal", {"friction": math.inf, "rate_bound": 20.0, "effort_coordinates": "absolute"}),
)
SWEEP_ARGS = ("--step-length", "0.45", "--period", "0.45", "--alpha-deg-range", "0", "45", "5",
              "--mode", "normal", "anti-normal")
WALK_RATE = 200.0  # samples per second of the stored walk

# ---------------------------------------------------------------------------------------------
# How precisely a figure is known, hence how far another machine may move it.
#
# FIGURE: a plan's figures are known to about 1e-10 of their size: the fixed RK8 grid's end state
# agrees with an adaptive integrator to about 1e-10 (docs/model.md section 4.8), the BVP closes to
# 1e-12, the LP's optimum is certified to its duality gap. Another machine's rounding moves them
# far less: a request moved by a few ulps moves every figure by at most 1e-12 of its size
# (measured on the 10 stored plans, the walk and the sweep). 1e-9 leaves room for both and still
# catches a change of the model, of a limit or of the solution branch.
FIGURE = 1e-9
# The stored multipliers were computed with the reset's Jacobian by central differences, which knew
# every multiplier to about 1e-8 of the spectral radius (measured: a few ulps in the request moved
# them by up to 7e-9 of it); the analytic Jacobian (docs/model.md section 8.9) is within that of
# them. Ten times those.
MULTIPLIER = 1e-7  # of the spectral radius, every multiplier
SPECTRAL_RADIUS = 5e-8  # of itself
# A touchdown instant is known to about 1e-12 s (the guard's root on the RK8 interpolant, the
# re-aimed durations to 1e-12); a sample taken within TOUCHDOWN_TIME of a touchdown may fall on
# either side of it, in either step.
TOUCHDOWN_TIME = 1e-9  # s


@dataclass(frozen=True)
class Same:
    """Equal: a word, a flag, a name list, a verdict (not computed in floating point)."""

    why: str

    def mismatch(self, now: Any, stored: Any) -> str:
        return "" if now == stored else f"{now!r} != stored {stored!r}"


def _array(value: Any) -> np.ndarray:
    """A figure as a float array, None (JSON's NaN and infinities) as NaN."""
    return np.array(value, dtype=float)


@dataclass(frozen=True)
class Close:
    """|now - stored| <= rtol x max(largest |stored| entry, floor), entry by entry (an array as
    a whole: its entries come from one solve and share its scale; ``floor``, in the figure's own
    unit, is the size below which the figure is physically zero, e.g. a velocity that vanishes by
    construction). None (a figure that is NaN or infinite) must stay None."""

    rtol: float
    why: str
    floor: float = 1.0

    def mismatch(self, now: Any, stored: Any) -> str:
        if stored is None or now is None:
            return "" if stored is None and now is None else f"{now!r} where {stored!r} was stored"
        a, b = _array(now), _array(stored)
        if a.shape != b.shape:
            return f"shape {a.shape} != stored {b.shape}"
        if not np.array_equal(np.isnan(a), np.isnan(b)):
            return "NaN where the stored figure has none, or the reverse"
        if b.size == 0:
            return ""
        tol = self.rtol * max(float(np.nanmax(np.abs(b))), self.floor)
        worst = float(np.nanmax(np.abs(a - b))) if np.any(~np.isnan(b)) else 0.0
        return "" if worst <= tol else f"moved by {worst:.3g}, more than {tol:.3g}"


@dataclass(frozen=True)
class Below:
    """A residual: |now| within ``bound`` (what the method guarantees), whatever its stored value
    (rounding is all it holds); None stays None."""

    bound: float
    why: str

    def mismatch(self, now: Any, stored: Any) -> str:
        if stored is None or now is None:
            return "" if stored is None and now is None else f"{now!r} where {stored!r} was stored"
        return "" if abs(now) <= self.bound else f"{now:.3g} beyond {self.bound:.3g}"


@dataclass(frozen=True)
class Count:
    """A count of the solver's work: within ``slack`` of the stored one."""

    slack: int
    why: str

    def mismatch(self, now: Any, stored: Any) -> str:
        return "" if abs(now - stored) <= self.slack else f"{now} != stored {stored} (within {self.slack})"


@dataclass(frozen=True)
class Spectrum:
    """Floquet multipliers ([re, im] pairs) as a set: each stored one within ``rtol`` times the
    spectral radius of a computed one, and the reverse (their order is a sort by modulus, which
    moves where two moduli are equal)."""

    rtol: float
    why: str

    def mismatch(self, now: Any, stored: Any) -> str:
        a, b = (np.array([complex(re, im) for re, im in v]) for v in (now, stored))
        if a.shape != b.shape:
            return f"{a.size} multipliers, {b.size} stored"
        if b.size == 0:
            return ""
        tol = self.rtol * float(np.max(np.abs(b)))
        worst = max(np.max(np.min(np.abs(a[:, None] - b[None, :]), axis=0)),
                    np.max(np.min(np.abs(a[:, None] - b[None, :]), axis=1)))
        return "" if worst <= tol else f"a multiplier moved by {worst:.3g}, more than {tol:.3g}"


@dataclass(frozen=True)
class Each:
    """A dictionary of figures, each by its own tolerance (``parts``)."""

    parts: dict
    why: str

    def mismatch(self, now: Any, stored: Any) -> str:
        if set(now) != set(stored):
            return f"keys {sorted(now)} != stored {sorted(stored)}"
        return "; ".join(f"{key}: {m}" for key, tol in self.parts.items() if key in stored
                         and (m := tol.mismatch(now[key], stored[key])))


INPUT = Close(1e-12, "the request itself, echoed (the ulp test moves it by a few ulps)")
WORD = Same("a word or a flag of the request or of the verdict")
PHYSICAL = Close(FIGURE, "a figure of the solution (FIGURE)")
ZERO_BY_CONSTRUCTION = Close(FIGURE, "zero by construction up to rounding: compared at the scale of the gait's "
                             "velocities, 1 m/s", floor=1.0)
_RK8_STAGES = 12


def _coarse_iteration() -> int:
    """Dynamics evaluations of one coarse-grid iteration: RK8 stages x coarse steps, and the end
    node's acceleration where the flow keeps its nodes (the chord step that settles the coarse
    solution a plan's estimate reads)."""
    from biped_gait.core.dynamics.settings import DEFAULTS

    return DEFAULTS.coarse_steps * _RK8_STAGES + 1


TOLERANCES: dict[str, Any] = {
    **{key: INPUT for key in ("step_length", "period", "arm_amplitude", "arm_amplitude_deg", "friction", "rate_bound", "step_width",
                              "turn_radius", "min_clearance", "friction_margin")},
    **{key: WORD for key in ("mode", "params", "closure", "effort", "effort_coordinates", "joint_names",
                             "actuated_joints", "double_support_coordinates", "converged", "admissible", "message",
                             "reasons", "found", "hint", "open_loop_stable", "within_limits")},
    **{key: PHYSICAL for key in ("theta", "slack", "W", "heading_change", "I_minus", "I_plus", "IR1_minus", "IR2",
                                 "IR2_plus", "reaction_spin_impulses", "Xd_minus", "Xd_plus", "Xd_a", "Xd_b", "qd_a",
                                 "qd_b", "q0", "qT", "new_stance_foot", "min_grf_z", "min_swing_height",
                                 "min_late_swing_height", "swing_arrival_speed", "max_friction_ratio", "q3_range",
                                 "q5_range", "H_Tminus", "H_Tplus", "old_stance_tip_vz_after_impact",
                                 "impulse_friction_ratios", "max_intermediate_joint_rate", "foot_line_moment")},
    # Zero by construction: the swing knee's least angle is 0 at the boundaries of the paper's sets,
    # the swing tip's vertical speed before the impact and the new stance tip's after it vanish.
    **{key: ZERO_BY_CONSTRUCTION for key in ("q9_min", "swing_tip_vz_before_impact", "new_stance_tip_speed_after")},
    "end_point_residual": Below(1e-12, "the BVP's tolerance (rad; settings.tolerance)"),
    "closure_residual": Below(1e-12, "the BVP's tolerance on the closure gap (kg m^2/s)"),
    "impact_equation_residual": Below(1e-10, "eqs. (6)-(10) at the LP's solution: the equality rows' rounding, "
                                      "measured up to 2e-12 (N s, N m s)"),
    "lp_duality_gap": Below(1e-9, "the LP's optimality certificate (N m s)"),
    "energy_drift": Below(1e-10, "the fixed RK8 grid's energy error over the step (J; 1e-14 measured)"),
    **{key: Below(bound, "the plan's estimate of its integration error: within the contract (docs/model.md 4.11)")
       for key, bound in (("integration_error_end_point", 1e-9), ("integration_error_W", 1e-8),
                          ("integration_error_figures", 1e-8))},
    "integration_error_samples": Below(1e-6, "the estimated error of the Hermite samples (1e-8 measured at 32 steps)"),
    "grid_steps": Count(0, "the RK8 grid the plan was solved on: the planner's own, not refined (the stored "
                           "plans' estimates are at most 1/19 of the contract's bounds: no rounding moves the decision)"),
    "bvp_iterations": Count(1, "Newton's iterations: the residual crosses the tolerance one iteration earlier or later"),
    "dynamics_evaluations": Count(_coarse_iteration(), "one coarse-grid iteration more or less"),
    "multipliers": Spectrum(MULTIPLIER, "the Jacobian's precision (MULTIPLIER)"),
    "multiplier_moduli": Close(MULTIPLIER, "sorted moduli, at the Jacobian's precision (MULTIPLIER)"),
    "spectral_radius": Close(SPECTRAL_RADIUS, "the leading multiplier's precision (SPECTRAL_RADIUS)", floor=0.0),
    "trajectory": Each({"t": INPUT, "q": PHYSICAL, "qd": PHYSICAL, "grf": PHYSICAL, "h_vertical": PHYSICAL},
                       "the sampled step"),
}


def mismatches(now: dict, stored: dict) -> list[str]:
    """Each stored figure that ``now`` lacks or moved beyond its tolerance, as 'key: why'."""
    out = []
    for key, value in stored.items():
        if key not in now:
            out.append(f"{key}: missing")
        elif m := TOLERANCES[key].mismatch(now[key], value):
            out.append(f"{key}: {m}")
    return out


def moved(x: float, ulps: int) -> float:
    """``x`` moved by ``ulps`` units in the last place (towards +inf for positive ``ulps``)."""
    for _ in range(abs(ulps)):
        x = float(np.nextafter(x, math.inf if ulps > 0 else -math.inf))
    return x


def plan_figures(params: str, ulps: int = 0) -> list[dict]:
    """The plan figures of each of ``REQUESTS`` for the parameter set ``params``, solve time left
    out; ``ulps``: L and alpha moved by that many ulps and T by as many the other way."""
    from biped_gait.core.gait import views
    from biped_gait.core.gait.planner import GaitPlanner, GaitRequest

    planner = GaitPlanner(params)
    out = []
    for length, period, alpha, mode, extra in REQUESTS:
        gait = planner.plan(GaitRequest(moved(length, ulps), moved(period, -ulps), moved(math.radians(alpha), ulps),
                                        mode, **extra))
        figures = views.to_dict(gait)
        figures.pop("solve_time_s")
        out.append(figures)
    return out


def stored_plans(params: str) -> list[dict]:
    """The stored plan figures of ``params``, in ``REQUESTS`` order."""
    return [json.loads(gzip.decompress((DATA / f"plan-{params}-{k}.json.gz").read_bytes()))
            for k in range(len(REQUESTS))]


def walk_arrays(ulps: int = 0) -> dict[str, np.ndarray]:
    """20 steps of the default gait walked with momentum steering at ``WALK_RATE`` samples per
    second (``ulps``: its request moved as ``plan_figures`` moves them)."""
    from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
    from biped_gait.core.walking.events import StepSamples, Touchdown
    from biped_gait.core.walking.orbit import PlannedOrbit
    from biped_gait.core.walking.walk import Walk

    gait = GaitPlanner().plan(GaitRequest(moved(0.45, ulps), moved(0.45, -ulps), moved(math.radians(23.5), ulps),
                                          "normal"))
    walk = Walk(PlannedOrbit.of(gait), rate=WALK_RATE, steps=20, momentum_rate=0.25)
    rows: dict[str, list] = {name: [] for name in ("t", "step", "q", "qd", "grf")}
    position, quaternion, impulses, times = [], [], [], []
    for item in walk.batches():
        if isinstance(item, StepSamples):
            for s in item.samples:
                for name, value in (("t", s.t), ("step", s.step), ("q", s.q), ("qd", s.qd), ("grf", s.grf)):
                    rows[name].append(value)
            position.append(item.world.pelvis_position)
            quaternion.append(item.world.pelvis_quaternion)
        elif isinstance(item, Touchdown):
            impulses.append(np.concatenate([item.i_minus, item.i_plus, [item.W]]))
            times.append([item.t, item.t_step])
    return {**{name: np.array(value) for name, value in rows.items()}, "pelvis_position": np.concatenate(position),
            "pelvis_quaternion": np.concatenate(quaternion), "touchdown_impulses": np.array(impulses),
            "touchdown_times": np.array(times)}


def walk_mismatches(now: dict[str, np.ndarray], stored: dict[str, np.ndarray]) -> list[str]:
    """How the walk ``now`` differs from ``stored`` beyond the tolerances: the touchdowns'
    instants within ``TOUCHDOWN_TIME``, their impulses and every sample's state, ground reaction
    and pelvis pose within ``FIGURE`` of their size (a few ulps in the request move them by 1e-12
    of it: the walk re-aims every step, so errors do not grow from step to step). Samples are
    matched by instant; one at an instant within ``TOUCHDOWN_TIME`` of a touchdown may lie in
    either step (before the touchdown, or opening the next step), and the walk's last instant
    may be taken or not."""
    out = []
    if now["touchdown_times"].shape != stored["touchdown_times"].shape:
        return [f"{len(now['touchdown_times'])} touchdowns, {len(stored['touchdown_times'])} stored"]
    if (m := Close(TOUCHDOWN_TIME, "", floor=1.0).mismatch(now["touchdown_times"].tolist(),
                                                          stored["touchdown_times"].tolist())):
        out.append(f"touchdown_times: {m}")
    if (m := PHYSICAL.mismatch(now["touchdown_impulses"].tolist(), stored["touchdown_impulses"].tolist())):
        out.append(f"touchdown_impulses: {m}")
    n_now, n_stored = len(now["t"]), len(stored["t"])
    n = min(n_now, n_stored)
    touchdowns = stored["touchdown_times"][:, 0]
    near = np.min(np.abs(stored["t"][:, None] - touchdowns[None, :]), axis=1) <= TOUCHDOWN_TIME
    if n_now != n_stored and (abs(n_now - n_stored) > 1 or abs(n / WALK_RATE - touchdowns[-1]) > TOUCHDOWN_TIME):
        out.append(f"{n_now} samples, {n_stored} stored")
    if not np.allclose(now["t"][:n], stored["t"][:n], rtol=0.0, atol=1e-12):
        out.append("the samples' instants moved")
    same = (now["step"][:n] == stored["step"][:n])
    if np.any(~same & ~near[:n]):
        out.append(f"samples in another step away from any touchdown: {np.flatnonzero(~same & ~near[:n])[:5]}")
    for name in ("q", "qd", "grf", "pelvis_position", "pelvis_quaternion"):
        a, b = now[name][:n][same], stored[name][:n][same]
        if (m := PHYSICAL.mismatch(a, b)):
            out.append(f"{name}: {m}")
    return out


def stored_walk() -> dict[str, np.ndarray]:
    with np.load(DATA / "walk.npz") as archive:
        return {name: archive[name] for name in archive.files}


def sweep_csv(ulps: int = 0) -> str:
    """The CSV of a small sweep over alpha, both modes, through the command line (the solve times
    left out; ``ulps``: L moved by that many ulps and T by as many the other way)."""
    args = list(SWEEP_ARGS)
    args[1], args[3] = repr(moved(float(args[1]), ulps)), repr(moved(float(args[3]), -ulps))
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([sys.executable, "-m", "biped_gait.cli", "sweep", *args, "--workers", "1", "--out", out],
                       check=True, capture_output=True)
        rows = list(csv.reader(io.StringIO((Path(out) / "sweep.csv").read_text())))
    keep = [k for k, name in enumerate(rows[0]) if name != "solve_time_s"]
    text = io.StringIO()
    csv.writer(text, lineterminator="\n").writerows([[row[k] for k in keep] for row in rows])
    return text.getvalue()


def _cell(text: str) -> Any:
    """A CSV cell as the JSON value it was written from (empty: None)."""
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    try:
        return json.loads(text.replace("nan", "null"))
    except json.JSONDecodeError:
        return text


def sweep_rows(text: str) -> list[dict]:
    """A sweep's CSV as one dictionary of figures per row."""
    rows = list(csv.reader(io.StringIO(text)))
    return [{name: _cell(cell) for name, cell in zip(rows[0], row)} for row in rows[1:]]


def atlas_hashes() -> dict[str, str]:
    """SHA-256 of every node array of every shipped atlas, by "file/array"."""
    from importlib import resources

    out = {}
    folder = resources.files("biped_gait").joinpath("core", "data", "atlas")
    for path in sorted(Path(str(folder)).glob("*.npz")):
        with np.load(path) as archive:
            for name in sorted(archive.files):
                if name != "meta":
                    out[f"{path.name}/{name}"] = hashlib.sha256(np.ascontiguousarray(archive[name]).tobytes()).hexdigest()
    return out
