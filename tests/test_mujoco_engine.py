"""The walk in MuJoCo (``engine="mujoco"``, core/walking/engines/mujoco.py): the single support
integrated by MuJoCo on the exported stance tree, the double support as torque pulses
(core/walking/phases/pulses.py), the walker's re-aim as the feedback. Against the hybrid walker, and 20 steps of the default gait."""

from __future__ import annotations

import math

import numpy as np
import pytest

from biped_gait.core.walking.push import AppliedPush, Push
from biped_gait.core.walking.steering import DEFAULT_RATE
from biped_gait.core.walking.events import Finished, StepSamples, Touchdown
from biped_gait.core.walking.orbit import PlannedOrbit
from biped_gait.core.walking.runner import Walker
from biped_gait.core.walking.walk import Walk

pytestmark = pytest.mark.core

CONFIGURATION_DRIFT = 4.5  # rad/s: the pre-impact pulse moves the touchdown configuration by at most this times d


@pytest.mark.parametrize("pulse", [1e-3, 5e-3])
def test_the_first_step_is_the_hybrid_walkers_but_for_the_pulse(planner, default_gait, pulse):
    """Started on the plan, MuJoCo's single support (RK4, 1 ms) is the hybrid walker's: the
    touchdown predicted from MuJoCo's state 10 ms before the pulse is the hybrid's to 1e-7 (rad,
    rad/s); MuJoCo's swing foot lands when the hybrid's does (1e-8 s), its configuration moved by
    the pre-impact pulse by at most CONFIGURATION_DRIFT d (measured: 3.9 rad/s d, from 0.5 to
    10 ms)."""
    orbit = PlannedOrbit.of(default_gait)
    hybrid = Walker(planner.hybrid, orbit, rate=100.0, momentum_rate=DEFAULT_RATE).walk_step().touchdown
    walk = Walk(orbit, 100.0, 1, engine="mujoco", pulse_duration=pulse, momentum_rate=DEFAULT_RATE)
    outcome = walk.walker.walk_step()
    mujoco = outcome.touchdown.double_support
    assert outcome.touchdown is not None and hybrid.state_error < 1e-9
    q_t, qd_b = default_gait.step.q_target, default_gait.step.qd_b
    print(f"\nd = {pulse * 1e3:g} ms: predicted touchdown off the hybrid's by "
          f"{np.max(np.abs(mujoco.q_predicted - q_t)):.1e} rad, {np.max(np.abs(mujoco.qd_predicted - qd_b)):.1e} rad/s; "
          f"MuJoCo's touchdown {mujoco.t - hybrid.t:.1e} s later, its configuration "
          f"{np.max(np.abs(mujoco.q - q_t)):.2e} rad off")
    assert np.max(np.abs(mujoco.q_predicted - q_t)) < 1e-7 and np.max(np.abs(mujoco.qd_predicted - qd_b)) < 1e-7
    assert abs(mujoco.t - hybrid.t) < 1e-8
    assert 0.1 * pulse < np.max(np.abs(mujoco.q - q_t)) < CONFIGURATION_DRIFT * pulse
    assert outcome.touchdown.t == mujoco.t
    assert mujoco.residual < 1e-7 and mujoco.friction_planned <= planner.model.params.friction + 1e-6
    mu = planner.model.params.friction
    assert all(math.hypot(*s.grf[:2]) <= mu * s.grf[2] for s in outcome.samples)  # MuJoCo's reaction in the cone


def test_mujoco_walks_the_default_gait_twenty_steps_with_5_ms_pulses(planner, default_gait):
    """The default gait (L = T = 0.45, alpha = 23.5 deg) in MuJoCo with pulses of 5 ms: 20 steps,
    every pulsed phase within the friction cone (MuJoCo's reaction at every sample, mu = 0.5), the
    vertical reaction positive, the effort within 10 % of the impulses' W (measured 35.4 against
    33.2 N m s), the feet L apart to 5 mm (measured 2.1 mm short: the pre-impact pulse moves the
    touchdown configuration)."""
    walk = Walk(PlannedOrbit.of(default_gait), 100.0, 20, engine="mujoco", pulse_duration=5e-3,
                momentum_rate=DEFAULT_RATE)
    items = list(walk.batches())
    touchdowns = [item for item in items if isinstance(item, Touchdown)]
    assert isinstance(items[-1], Finished) and items[-1].steps == 20 and len(touchdowns) == 20
    mu = planner.model.params.friction
    records = [td.double_support for td in touchdowns]
    for record in records:
        assert record.residual < 1e-7
        assert record.friction_planned <= mu + 1e-6
        assert record.effort == pytest.approx(record.impulsive_effort, rel=0.1)
    # The torques that act at the samples: none in the ballistic single support, a pulse's (u^- of
    # the step's record, u^+ of the one before) within the pulses.
    torques = [s.torque[planner.model.actuated] for item in items if isinstance(item, StepSamples) for s in item.samples]
    pulses = [u for record in records for u in (record.u_minus, record.u_plus)]
    pulsed = [u for u in torques if np.any(u)]
    assert pulsed and all(any(np.array_equal(u, pulse) for pulse in pulses) for u in pulsed)
    print(f"samples in a pulse: {len(pulsed)} of {len(torques)}")
    grf = np.vstack([np.array([s.grf for s in item.samples]) for item in items if isinstance(item, StepSamples)])
    used = np.hypot(grf[:, 0], grf[:, 1]) / grf[:, 2]
    assert np.min(grf[:, 2]) > 0 and np.max(used) <= mu
    durations = [td.t_step for td in touchdowns]
    print(f"\n20 steps in MuJoCo, d = 5 ms: durations {min(durations):.4f}-{max(durations):.4f} s, effort "
          f"{records[-1].effort:.2f} N m s (W {records[-1].impulsive_effort:.2f}), friction used {np.max(used):.3f}")
    foot = walk.walker.state.stance_foot
    print(f"stance foot after 20 steps: {foot} m (steps of {foot[0] / 20:.4f} m: the pre-impact pulse moves the landing)")
    assert abs(foot[0] / 20 - 0.45) < 0.005 and foot[1:] == pytest.approx([-0.2, 0.0], abs=1e-9)
    assert all(math.isfinite(d) and abs(d - default_gait.period) < 0.01 for d in durations)


def test_an_unknown_engine_or_a_pulse_that_does_not_last_is_refused(default_gait):
    orbit = PlannedOrbit.of(default_gait)
    with pytest.raises(ValueError, match="unknown engine 'ode'"):
        Walk(orbit, 100.0, 1, engine="ode")
    with pytest.raises(ValueError, match="pulse duration must be positive"):
        Walk(orbit, 100.0, 1, engine="mujoco", pulse_duration=0.0)


def test_a_push_is_walked_off_in_mujoco(default_gait):
    """A push of 0.25 N s forward on the trunk at 0.3 T of step 1 acts on MuJoCo's state (the runner
    cuts MuJoCo's step there and adds the velocity jump, as in the hybrid walk); the walk re-plans
    when the touchdown is due (the planner's model after the push) and walks it off as the hybrid
    walker does (measured touchdown errors 0.41, 4.47, 0.83, 0.35, 0.32 rad/s against the hybrid's
    0.42, 5.2, 0.92, 0.20, 0.05)."""
    def push_in_step_1(walker: Walker) -> None:
        if walker.state.step == 1:
            walker.push(Push(np.array([0.25, 0.0, 0.0]), 0.3 * default_gait.period))

    walk = Walk(PlannedOrbit.of(default_gait), 100.0, 6, engine="mujoco", momentum_rate=DEFAULT_RATE,
                before_step=push_in_step_1)
    items = list(walk)
    pushes = [item for item in items if isinstance(item, AppliedPush)]
    errors = [item.state_error for item in items if isinstance(item, Touchdown)]
    assert isinstance(items[-1], Finished) and len(errors) == 6
    assert len(pushes) == 1 and pushes[0].step == 1 and np.max(np.abs(pushes[0].delta_qd)) > 0.01
    assert pushes[0].time_in_step == pytest.approx(0.3 * default_gait.period, abs=1e-12)  # at its instant
    assert errors[2] > 1.0 and errors[-1] < 0.5  # knocked off, and back to the 5 ms walk's (0.27)


@pytest.mark.parametrize("name", ["aoustin2013", "aoustin2013-hips"])
def test_the_floating_robot_is_the_models_state(planner, hips, name):
    """The model's state placed on MuJoCo's floor (engines/floating.py) is measured back to rounding,
    the stance tip at the origin and the swing tip where the model has it; the joint torques do the
    same power in both (the motors' signs are the coordinates')."""
    import mujoco

    from biped_gait.core.walking.engines.floating import FloatingRobot

    chosen = planner if name == "aoustin2013" else hips
    bm = chosen.model
    floating = FloatingRobot(chosen.hybrid.samples, 1e-3)
    data = floating.data()
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, qd, torque = rng.uniform(-0.4, 0.4, bm.nq), rng.normal(size=bm.nq), rng.normal(size=len(bm.actuated))
        floating.place(data, q, qd)
        measured_q, measured_qd = floating.measure(data)
        assert np.max(np.abs(measured_q - q)) < 1e-12 and np.max(np.abs(measured_qd - qd)) < 1e-12
        tips = floating.tips(data)
        assert np.max(np.abs(tips[0])) < 1e-12 and np.max(np.abs(tips[1] - bm.swing_tip(q))) < 1e-12
        floating.apply(data, torque)
        mujoco.mj_forward(floating.model, data)
        assert float(data.qfrc_actuator @ data.qvel) == pytest.approx(float(torque @ qd[bm.actuated]), abs=1e-10)
