"""Starting from standing and stopping standing (core/walking/start_stop.py, docs/model.md
section 8.10): the homotopies start on the gait's own step, the double support to rest stops
every velocity when the feet-line momentum is zero and the floor's friction allows it, and for
the default gait both the stop and the start are refused with their physical reasons."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest

from biped_gait.core.dynamics.impulses import EffortOptions
from biped_gait.core.walking import start_stop
from biped_gait.core.walking.start_stop import StartStopError, com_friction, double_support, plan_start, plan_stop
from biped_gait.core.walking.steering import momentum_row
from biped_gait.core.walking.orbit import PlannedOrbit

pytestmark = pytest.mark.core

GRID = 32


@pytest.fixture(scope="module")
def orbit(default_gait) -> PlannedOrbit:
    return PlannedOrbit.of(default_gait)


def test_the_homotopies_start_on_the_gaits_own_step(planner, orbit):
    """At the homotopy's start (both momenta the gait's M_p), the gait's step solves the stop's
    and the start's equations: the stop with L_s = L, the start with theta_s = theta_p."""
    hybrid = planner.hybrid
    m_p, theta = start_stop.orbit_momentum(hybrid, orbit), start_stop.orbit_theta(hybrid, orbit)
    assert 8.0 < m_p < 25.0  # kg m^2/s: no single double support removes it
    q_t = np.asarray(orbit.q_t)
    pose = lambda length, pitch: start_stop.pose_configuration(hybrid, orbit, start_stop.Pose(length, pitch))  # noqa: E731
    stop = start_stop._Leg(hybrid, hybrid.flow(GRID), lambda p: q_t, lambda p: pose(p, theta), m_p, m_p)
    start = start_stop._Leg(hybrid, hybrid.flow(GRID), lambda p: pose(orbit.step_length, p), lambda p: q_t, m_p, m_p)
    for leg, p in ((stop, orbit.step_length), (start, theta)):
        f, jac, _ = leg(np.concatenate([orbit.qd_a, [orbit.period, p]]), True)
        assert np.max(np.abs(f)) < 1e-9 and np.linalg.cond(jac) < 1e8


def test_the_double_support_to_rest_stops_everything_when_it_can(planner, orbit):
    """At the gait's touchdown configuration, the swing knee folding at 1 rad/s (moved to zero
    feet-line momentum): on a floor without friction limit the LP brings every velocity to 0 (to
    1e-9), the vertical reactions non-negative; on the default floor (mu = 0.5) it is refused, with
    the friction the CoM's change of velocity needs at least. From the gait's own pre-impact
    velocity (moved alike) there is no rest even without the cone."""
    hybrid, q_t = planner.hybrid, np.asarray(orbit.q_t)
    row = momentum_row(hybrid, q_t)
    folding = np.zeros(hybrid.bm.nq)
    folding[hybrid.bm.index("knee", "swing")] = 1.0
    arriving = folding - (row @ folding) / (row @ row) * row
    assert abs(row @ arriving) < 1e-12
    frictionless = replace(orbit, options=EffortOptions())
    rest = double_support(hybrid, frictionless, q_t, arriving, None, "to rest")
    print(f"\nto rest: W = {rest.W:.2f} N m s, friction needed {np.round(rest.friction_ratios, 3)}, "
          f"final velocity {np.max(np.abs(rest.after)):.1e} rad/s")
    assert np.max(np.abs(rest.after)) < 1e-9 and rest.impulses.equation_residual < 1e-9
    assert min(rest.impulses.ir1_minus[2], rest.impulses.ir2[2], rest.impulses.ir2_plus[2]) >= -1e-9
    needed = com_friction(hybrid, q_t, hybrid.bm.embed(arriving), np.zeros(hybrid.bm.double_support.nv))
    with pytest.raises(StartStopError, match=rf"alone needs mu >= {needed:.3g}.*the floor's mu = 0.5"):
        double_support(hybrid, orbit, q_t, arriving, None, "to rest")
    qd_b = np.asarray(orbit.qd_b)
    walking = qd_b - (row @ qd_b) / (row @ row) * row
    with pytest.raises(StartStopError, match="needs mu >= 3.3"):
        double_support(hybrid, frictionless, q_t, walking, None, "to rest")


def test_the_stop_from_the_default_gait_is_refused_by_the_legs_reach(planner, orbit):
    """Lengthening the stop step is the branch that lowers the arrival momentum; it reaches the
    legs' reach (2 l = 1.814 m) before the momentum reaches zero."""
    with pytest.raises(StartStopError) as refusal:
        plan_stop(planner.hybrid, orbit, GRID)
    message = str(refusal.value)
    print(f"\n{message}")
    found = re.search(r"beyond (\d+) % of the way .* L_s = ([\d.]+) m, the legs' reach 1.814 m", message)
    assert found and 50 <= int(found.group(1)) < 100 and 1.5 < float(found.group(2)) < 1.814


def test_the_start_from_standing_at_the_default_gait_is_refused(planner, orbit):
    """The start's branch ends at a step of 0.07 s from a trunk pitched about 52 deg forward,
    which the ground would have to pull on: refused with its ground reaction."""
    with pytest.raises(StartStopError) as refusal:
        plan_start(planner.hybrid, orbit, GRID)
    message = str(refusal.value)
    print(f"\n{message}")
    found = re.search(r"the start step from theta_s = ([\d.]+) deg \(T = ([\d.]+) s\) cannot be walked: vertical "
                      r"ground reaction not positive", message)
    assert found and 40 < float(found.group(1)) < 65 and float(found.group(2)) < 0.15


def test_a_turning_gait_is_refused(planner, orbit):
    with pytest.raises(StartStopError, match="straight gaits only"):
        plan_stop(planner.hybrid, replace(orbit, turn_radius=2.0), GRID)
    assert "straight gaits only" in start_stop.why_not("start", planner.hybrid, replace(orbit, turn_radius=-3.0), GRID)
