"""The stop as a B-spline (core/gait/spline_stop.py, docs/model.md section 14): its mesh, the kept
stop of the default gait checked against the model's own dynamics (not the program's), and that
stop walked in the hybrid engine from the held touchdown into standing."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from biped_gait.core.dynamics.closed_chain import ClosedChain
from biped_gait.core.dynamics.samples import SampleEvaluator
from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.gait.lasting import LastingRequest
from biped_gait.core.gait.spline_stop import (FIRST_INTERVAL, LONGEST_INTERVAL, SAMPLE_STEP, SplineStopProgram,
                                              kept_stop_path, load_stop, seed, spline_mesh)
from biped_gait.core.walking.balance import balance, standing_pose
from biped_gait.core.walking.engines.engine import Held, Motion
from biped_gait.core.walking.engines.hybrid import HybridEngine
from biped_gait.core.walking.held_support import held_support
from biped_gait.core.walking.reaction_guard import guarded_torque

# What the kept plan holds, and how well: IPOPT's constraint tolerance is 1e-6 (N, N m, rad) on
# scaled rows; the held impact and I^- are rows of the program, so the plan's first velocity is
# theirs to that; the equations of motion at the samples to 1e-4 N m (measured 2e-9).
ROWS = 1e-4  # N m, N
VELOCITY = 1e-6  # rad/s
STEP = 1e-3  # s: the walk's step
STANDING = 4.0  # s of standing after the stop (the pelvis under 1 mm/s from 1.5 s on, measured) ...
STILL = 1e-3  # m/s: ... the pelvis's speed under this over its last 2 s (the stop and start issue's test)


@pytest.fixture(scope="module")
def kept():
    planner = GaitPlanner(modes=("normal",))
    support, meta = load_stop(kept_stop_path(), planner.model)
    gait = planner.plan(GaitRequest(meta["L"], meta["T"], meta["alpha"]))
    chain = ClosedChain(planner.model, planner.hybrid.exchange)
    pose = standing_pose(chain, meta["L"])
    return planner, gait, chain, pose, support, meta


def test_the_mesh_grades_its_knots_and_holds_the_roll_where_it_must():
    d = 2.0
    mesh = spline_mesh(d, 0.1)
    steps = np.diff(np.unique(mesh.knots)) * d
    assert steps[0] == pytest.approx(FIRST_INTERVAL)
    assert np.all(np.diff(steps[:-1]) >= -1e-15) and steps[:-1].max() <= LONGEST_INTERVAL + 1e-12
    assert 0.5 * LONGEST_INTERVAL <= steps[-1] <= 1.5 * LONGEST_INTERVAL
    assert len(mesh.closure) == mesh.control_points - 5  # three end conditions at s = 1, two at s = 0
    every = np.linspace(0.0, 1.0, int(round(d / SAMPLE_STEP)) + 1)
    assert all(np.min(np.abs(mesh.samples - s)) < 1e-12 for s in np.concatenate([every, mesh.closure]))
    t = mesh.samples * d
    assert not mesh.roll[-1]  # at rest the rest rows imply it
    assert mesh.roll[(t < 0.1) | ((t > d - 0.1) & (t < d))].all()
    middle = (t > 0.1) & (t < d - 0.1)
    at_closure = np.array([np.min(np.abs(mesh.closure - s)) < 1e-12 for s in mesh.samples])
    assert np.array_equal(mesh.roll[middle], at_closure[middle])
    assert np.array_equal(spline_mesh(d, 0.0).roll[1:-1], at_closure[1:-1])  # without the ends' rows
    with pytest.raises(ValueError, match="positive duration"):
        spline_mesh(0.0)


def test_the_seed_meets_the_programs_ends_and_closure(kept):
    """The least-acceleration seed (its own rows) against the program's rows (``_phase``'s), on a
    short stop that builds in seconds: the ends and the new tip held at the closure points."""
    planner, gait, chain, pose, support, meta = kept
    lasting = planner.lasting
    boundary = lasting.boundary(gait, pose.q)
    collocation = lasting.stop(gait, LastingRequest(1.0, "l1", 50.0, 0.1), pose.q)
    assert collocation.success, collocation.message
    program = SplineStopProgram(lasting.bm, spline_mesh(0.3), "l1", lasting.friction, lasting.exchange, lasting.flow)
    x0 = seed(program, boundary, lasting.program("stop", "l1").values(collocation.solution))
    problem = program._warm[0]
    params = np.concatenate([boundary.q_t, boundary.q_rest, boundary.xd_b, boundary.xd_a, [0.3, 0.0, 0.5]])
    rows = np.array(ca.Function("g", [problem["x"], problem["p"]], [problem["g"]])(x0, params)).ravel()
    names = np.array(program.row_names)
    kinematic = np.isin(names, ["the first posture", "the first velocity", "the last posture", "at rest",
                                "the new tip held"])
    # the two ends' postures, the first velocity, the last velocity and acceleration; x and z held
    assert kinematic.sum() == 5 * program.nq + 2 * len(program.mesh.closure)
    assert np.abs(rows[kinematic]).max() < 1e-6  # IPOPT's default tolerance on the seed's small program
    assert np.all(x0 >= program.lbw - 1e-12) and np.all(x0 <= program.ubw + 1e-12)


def test_the_kept_stop_starts_at_the_gaits_held_touchdown_and_ends_at_rest(kept):
    planner, gait, chain, pose, support, meta = kept
    assert meta["success"] and meta["duration"] == support.duration == pytest.approx(2.0)
    boundary = planner.lasting.boundary(gait, pose.q)
    at = chain.at
    # I^- with the old tip held, then the passive impact with both tips held: the model's own.
    d = planner.model.mass_matrix(boundary.q_t)
    before = boundary.xd_b[at] + np.linalg.solve(d[np.ix_(at, at)], chain.selection @ support.i_minus)
    impact = chain.impact(boundary.q_t, before)
    assert np.abs(support.x[0, at] - boundary.q_t).max() < VELOCITY
    assert np.abs(support.xd[0, at] - impact.qd).max() < VELOCITY
    assert impact.old[2] > -ROWS and impact.new[2] > -ROWS  # the landing presses (softly: about 0)
    assert np.abs(support.x[-1, at] - pose.q).max() < VELOCITY
    assert np.abs(support.xd[-1]).max() < VELOCITY and np.abs(support.xdd[-1]).max() < ROWS


def test_the_kept_stop_holds_the_chains_dynamics_and_the_floors_margins(kept):
    planner, gait, chain, pose, support, meta = kept
    bm, at = planner.model, chain.at
    mesh = spline_mesh(support.duration)
    assert np.allclose(support.t, mesh.samples * support.duration, atol=1e-12)
    residual = []
    for q, qd, qdd, torque, force in zip(support.x[:, at], support.xd[:, at], support.xdd[:, at],
                                         support.torques, support.contact_forces[:, 1]):
        generalized = pin.rnea(chain.ds, chain.ds_data, bm.ds_state(q), bm.embed(qd), bm.embed(qdd))[at]
        residual.append(generalized - chain.selection @ torque - chain.rows_of(q).T @ force[chain.rows])
    residual = np.abs(np.array(residual))
    assert residual[:, 1:].max() < ROWS  # every row with a torque or a reaction in it, at every sample
    assert residual[mesh.roll, 0].max() < ROWS  # the roll row where the mesh holds it
    assert residual[:, 0].max() < 10.0  # elsewhere the spline misses it by a few N m (measured 2.9)
    assert np.abs(support.torques).max() <= 200.0 + ROWS
    for k, c in enumerate(bm.coordinates):  # the joint table's ranges (a stance-leg coordinate inverted)
        low, high = (-c.spec.limits.upper, -c.spec.limits.lower) if c.inverted else (c.spec.limits.lower,
                                                                                     c.spec.limits.upper)
        assert low - ROWS <= support.x[:, at[k]].min() and support.x[:, at[k]].max() <= high + ROWS, c
    forces = support.contact_forces
    assert forces[..., 2].min() >= meta["least_normal_force"] - ROWS
    ratio = np.hypot(forces[..., 0], forces[..., 1]) / forces[..., 2]
    assert ratio.max() <= meta["friction"] + ROWS  # the octagonal pyramid lies within its cone
    tip = np.array([bm.swing_tip(q) for q in support.x[:, at]])
    assert np.abs(tip - tip[0])[:, [0, 2]].max() < 1e-4  # held at the closure points, within 0.1 mm between


def test_the_kept_stop_walks_into_standing_in_the_hybrid_engine(kept):
    planner, gait, chain, pose, support, meta = kept
    plan = held_support(chain, support)  # refused if its reference pulls a foot between samples
    engine, mu = HybridEngine(planner.hybrid), planner.model.params.friction
    stand = balance(chain, pose)
    stop = Motion(STEP, held=Held(chain, lambda t, q, qd: guarded_torque(chain, q, qd, plan.law(t, q, qd),
                                                                         plan.limits)))
    standing = Motion(STEP, held=Held(chain, lambda t, q, qd: stand.torque(q, qd)))
    ws = engine.workspace()
    engine.begin(ws, stop, 0.0, 0.0, support.x[0, chain.at], support.xd[0, chain.at])
    worst_error, least, widest, standing_states = 0.0, np.inf, 0.0, []
    for motion, end in ((stop, support.duration), (standing, support.duration + STANDING)):
        while ws.t < end - STEP / 2:
            t, q, qd = ws.t, ws.q, ws.qd
            torque = motion.held.law(t, q, qd)
            assert np.abs(torque).max() <= 200.0 + 1e-9
            qdd, held = chain.forward(q, qd, torque)
            wrench = chain.shared_wrenches(q, qd, qdd, held)
            least = min(least, wrench[:, 2].min())
            widest = max(widest, (np.hypot(wrench[:, 0], wrench[:, 1]) / wrench[:, 2]).max())
            if motion is stop:
                worst_error = max(worst_error, np.abs(q - plan.reference(t)[0]).max())
            else:
                standing_states.append((q, qd))
            engine.advance(ws, motion, end, math.inf)
    assert least > 0.0 and widest < mu  # both feet down and within the floor's cone at every step
    assert worst_error < 0.01  # rad: tracked (measured 7.1 mrad)
    q, qd = (np.array(rows) for rows in zip(*standing_states[-int(2.0 / STEP):]))
    speeds = np.linalg.norm(SampleEvaluator(planner.model).poses(q, qd).pelvis_linear_velocity, axis=1)  # /odom's
    assert speeds.max() < STILL
    assert np.abs(ws.q - pose.q).max() < 1e-3
