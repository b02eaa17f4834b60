"""Walks stored before the walk became a sequence of phases (issue 27), compared within tolerances
after it (tests/test_phases.py): today's gaits walked by the phase runner must give the figures
the walker gave.

Each walk is of stored orbits (``orbits.npz``: the plans' boundary states, so that a change of
the planner's last digits does not move them), with what exercises the runner: momentum steering
and a push in a step and one after its touchdown; the plain re-aim; a transition step to
another gait; a stride on a circle with the 13-joint set; MuJoCo with the double support as 5 ms
torque pulses. Stored per touchdown: its time in the walk and the step's duration (s), the
impulses I^-, I^+ (N m s, the pulses' integrals in MuJoCo) and W (N m s), the state error (rad,
rad/s); per step's start after it: q, qd (rad, rad/s), the stance foot (m) and the heading (rad).
Regenerate (only when the figures are meant to change) with

    .venv/bin/python -m tests.phase_walks
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data" / "phases"
# name: (parameter set, L m, T s, alpha deg, turn radius m)
GAITS = {
    "default": ("aoustin2013", 0.45, 0.45, 23.5, math.inf),
    "longer": ("aoustin2013", 0.50, 0.47, 23.5, math.inf),
    "circle": ("aoustin2013-hips", 0.45, 0.45, 20.0, 5.0),
}
ORBIT_FIELDS = ("q0", "q_t", "qd_a", "qd_b", "foot_line_moment", "theta")


def planned_orbits() -> dict[str, tuple]:
    """The orbits of ``GAITS`` as planned now: one per straight gait, a stride's two on the circle."""
    from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
    from biped_gait.core.walking.orbit import PlannedOrbit

    out = {}
    for name, (params, length, period, alpha, radius) in GAITS.items():
        planner = GaitPlanner(params)
        request = GaitRequest(length, period, math.radians(alpha), "normal", turn_radius=radius)
        steps = planner.plan_stride(request).steps if math.isfinite(radius) else (planner.plan(request),)
        out[name] = tuple(replace(PlannedOrbit.of(step), params=params) for step in steps)
    return out


def stored_orbits() -> dict[str, tuple]:
    """The orbits of ``GAITS`` with the boundary states stored with the walks."""
    orbits = planned_orbits()
    with np.load(DATA / "orbits.npz") as stored:
        return {name: tuple(replace(orbit, **{f: stored[f"{name}/{k}/{f}"] if stored[f"{name}/{k}/{f}"].ndim
                                              else float(stored[f"{name}/{k}/{f}"]) for f in ORBIT_FIELDS})
                            for k, orbit in enumerate(cycle))
                for name, cycle in orbits.items()}


def walks(orbits: dict[str, tuple]) -> dict:
    """The stored walks' ``Walk`` objects, each with what is done before its steps."""
    from biped_gait.core.walking.push import Push

    def pushes(walker) -> None:
        if walker.state.step == 1:
            walker.push(Push(np.array([0.3, 0.0, 0.0]), 0.5 * walker.period))
            walker.push(Push(np.array([0.0, 0.5, 0.0]), 0.2 * walker.period))
        if walker.state.step == 3:
            walker.push(Push(np.array([0.01, 0.0, 0.0]), 5.0))  # after the touchdown: on its pre-impact state

    def transition(walker) -> None:
        if walker.state.step == 2:
            walker.retarget(orbits["longer"])

    return {
        "steered": (orbits["default"], dict(rate=200.0, steps=8, momentum_rate=0.25), pushes),
        "plain": (orbits["default"], dict(rate=100.0, steps=6), None),
        "transition": (orbits["default"], dict(rate=100.0, steps=6, momentum_rate=0.25), transition),
        "circle": (orbits["circle"], dict(rate=50.0, steps=6, momentum_rate=0.25), None),
        "mujoco": (orbits["default"], dict(rate=100.0, steps=6, momentum_rate=0.25, engine="mujoco",
                                           pulse_duration=5e-3), None),
    }


def walk_figures(orbit, options: dict, before) -> dict[str, np.ndarray]:
    """The figures of one walk (module docstring), as arrays with one row per touchdown."""
    from biped_gait.core.walking.events import Finished, Touchdown
    from biped_gait.core.walking.walk import Walk

    starts = []

    def before_step(walker) -> None:
        s = walker.state
        starts.append(np.concatenate([s.q, s.qd, s.stance_foot, [s.heading]]))
        if before is not None:
            before(walker)

    walk = Walk(orbit, before_step=before_step, **options)
    touchdowns, end = [], None
    for item in walk.batches():
        if isinstance(item, Touchdown):
            touchdowns.append(item)
        elif isinstance(item, Finished):
            end = item
    assert end is not None and len(touchdowns) == options["steps"], "the walk did not finish"
    s = walk.walker.state
    starts.append(np.concatenate([s.q, s.qd, s.stance_foot, [s.heading]]))
    return {
        "times": np.array([[td.t, td.t_step] for td in touchdowns]),
        "impulses": np.array([np.concatenate([td.i_minus, td.i_plus]) for td in touchdowns]),
        "W": np.array([td.W for td in touchdowns]),
        "state_error": np.array([td.state_error for td in touchdowns]),
        "starts": np.array(starts[1:]),
    }


def main() -> None:
    DATA.mkdir(parents=True, exist_ok=True)
    orbits = planned_orbits()
    np.savez_compressed(DATA / "orbits.npz", **{f"{name}/{k}/{f}": np.asarray(getattr(orbit, f))
                                                for name, cycle in orbits.items() for k, orbit in enumerate(cycle)
                                                for f in ORBIT_FIELDS})
    orbits = stored_orbits()
    figures = {}
    for name, (orbit, options, before) in walks(orbits).items():
        figures.update({f"{name}/{key}": value for key, value in walk_figures(orbit, options, before).items()})
    np.savez_compressed(DATA / "walks.npz", **figures)


if __name__ == "__main__":
    main()
