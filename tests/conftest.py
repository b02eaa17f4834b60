"""Shared fixtures: one planner per parameter set and the default gait, solved once; under
pytest-xdist (tools/test.sh runs one worker per core), a ROS domain for each worker and the tests
marked ``paced`` run alone."""

from __future__ import annotations

import fcntl
import math
import os
import random
import shutil
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

# Every ROS process of the test session (this one and the nodes it starts) keeps DDS discovery
# on this machine and uses a domain of its own, so parallel sessions do not see each other. They
# talk over UDP on loopback alone: Fast DDS's shared-memory transport can leave a node restarted
# beside one that stays up unheard (biped_gait/ros/environment.py).
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ["FASTDDS_BUILTIN_TRANSPORTS"] = "UDPv4"
os.environ.setdefault("ROS_DOMAIN_ID", str(random.SystemRandom().randint(1, 100)))
# pytest-xdist's workers (gw0, gw1, ...) inherit the session's domain: worker k takes the k-th of
# distinct domains in 1..232 (Fast DDS's range; 101 and 232 are coprime), so that the nodes of
# two workers, which have the same names, never meet.
WORKER = os.environ.get("PYTEST_XDIST_WORKER")
if WORKER and "BIPED_GAIT_SESSION_DOMAIN" not in os.environ:
    os.environ["BIPED_GAIT_SESSION_DOMAIN"] = os.environ["ROS_DOMAIN_ID"]
    os.environ["ROS_DOMAIN_ID"] = str((int(os.environ["ROS_DOMAIN_ID"]) + 101 * int(WORKER[2:]) - 1) % 232 + 1)
# The lock the workers share (the controller names it): a test marked ``paced`` holds it alone,
# every other test shares it.
os.environ.setdefault("BIPED_GAIT_TEST_LOCK", os.path.join(tempfile.gettempdir(), f"biped-gait-tests-{os.getpid()}"))
# Solves kept on disk (biped_gait/core/gait/solve_cache.py) for this session alone: its workers and
# the nodes they start share them; none from an earlier run or from the user's own cache.
os.environ["BIPED_GAIT_CACHE"] = os.environ["BIPED_GAIT_TEST_LOCK"] + ".solves"

import numpy as np
import pytest

from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.dynamics.impulses import ImpactLayout, ImpactProblem

DEFAULT_REQUEST = GaitRequest(step_length=0.45, period=0.45, arm_amplitude=math.radians(23.5), mode="normal")


@pytest.fixture(scope="session")
def planner() -> GaitPlanner:
    return GaitPlanner()


@pytest.fixture(scope="session")
def hips() -> GaitPlanner:
    """The planner of the 13-DOF set (a yaw, a roll and a pitch joint in each hip)."""
    return GaitPlanner("aoustin2013-hips")


@pytest.fixture(scope="session")
def default_gait(planner):
    return planner.plan(DEFAULT_REQUEST)


def impact_problem(planner: GaitPlanner, gait) -> ImpactProblem:
    """Rebuild eqs. (6)-(10) for a solved gait from its reported velocities, with Pinocchio
    directly (not through the hybrid step's impact map, so that the two paths are compared)."""
    bm = planner.model
    q_t = gait.step.q_target
    j1, j2 = bm.tip_jacobians(q_t)
    tip = bm.swing_tip(q_t)
    z_d = np.zeros(12)
    z_d[3:5] = tip[:2] / np.linalg.norm(tip)  # the locked rotation about the foot-to-foot line
    return ImpactProblem(bm.mass_matrix(q_t), j1, j2, gait.double_support.xd_b, gait.double_support.xd_a, z_d,
                         ImpactLayout.of(bm))


@contextmanager
def _lock(exclusive: bool):
    """The session's lock, shared or exclusive, with a turnstile that an exclusive taker holds
    while it waits (so that the tests sharing the lock cannot keep a paced test waiting)."""
    base = os.environ["BIPED_GAIT_TEST_LOCK"]
    with open(base + ".turnstile", "a") as turnstile, open(base + ".lock", "a") as lock:
        fcntl.flock(turnstile, fcntl.LOCK_EX)
        if not exclusive:
            fcntl.flock(turnstile, fcntl.LOCK_UN)
        fcntl.flock(lock, fcntl.LOCK_EX if exclusive else fcntl.LOCK_SH)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
            fcntl.flock(turnstile, fcntl.LOCK_UN)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """Under pytest-xdist, a test that checks real-time pacing (marker ``paced``) runs with no other
    test running, from the set-up of its fixtures to their teardown; the others run side by side."""
    if WORKER is None:
        yield
        return
    with _lock(item.get_closest_marker("paced") is not None):
        yield


# The modules that take longest (their solves, walks and nodes' start-ups: 6 to 130 s each on the
# 2 cores of a full run at cdb4887), longest first. pytest-xdist (tools/test.sh: --dist loadscope
# --no-loadscope-reorder) hands each worker a module at a time in collection order, so these go first
# and the short modules, after them, even out the workers' ends; its own order, by the number of
# tests, left long modules of few tests for last, one worker walking on alone. The order changes no
# test's outcome; a module missing here only starts later. test_actuated_walk and test_lasting_hips,
# whose set-ups are the suite's two longest cold solves (IPOPT, 80 to 120 s each, one core each), side
# by side once the first two modules are done, when no test marked ``paced`` is left to wait for
# either: a paced test waits for the other worker's test in progress, and a set-up is one test.
# test_actuated_ros after test_actuated_walk by four modules: its planner takes the walkable actuated
# swing that test_actuated_walk solved and kept (solve_cache), where at once it would wait for that
# solve with its worker idle. test_simulator_node (a paced test) among the modules of short tests, its
# wait for the other worker's test in progress short.
LONGEST_FIRST = ("test_study_cli", "test_faults_nodes", "test_actuated_walk", "test_lasting_hips", "test_planner_node",
                 "test_simulator_turning", "test_actuated_ros", "test_doc_examples", "test_lasting",
                 "test_actuated_swing", "test_faults_inputs", "test_simulator_lasting", "test_standing",
                 "test_simulator_standing", "test_simulator_walking", "test_walking_page", "test_simulator_start_stop",
                 "test_dask", "test_lasting_walk", "test_spline_support", "test_turning", "test_hips_speeds", "test_sim_time", "test_atlas",
                 "test_conversions", "test_simulator_node", "test_replay", "test_launch", "test_analyze", "test_sweep",
                 "test_optimize", "test_walk", "test_cli", "test_speed", "test_reference_figures",
                 "test_effort_options")


@pytest.fixture(autouse=True)
def _no_node_left_running():
    """Stop the node processes a test started and left running (it failed before stopping them):
    in its worker's ROS domain such a node would publish into the next tests' topics, and one
    failure would become many. The nodes of module fixtures, started before this fixture, are
    theirs to stop."""
    helpers = sys.modules.get("tests.ros_helpers")
    first = len(helpers.STARTED) if helpers is not None else 0
    yield
    helpers = sys.modules.get("tests.ros_helpers")
    if helpers is None:
        return
    for proc in helpers.STARTED[first:]:
        if proc.poll() is None:
            helpers.stop_node(proc)


def pytest_collection_modifyitems(config, items):
    """The modules of ``LONGEST_FIRST`` first, in its order; the others after them as collected."""
    rank = {name: k for k, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(Path(item.nodeid.split("::")[0]).stem, len(rank)))


def pytest_unconfigure(config):
    if WORKER is None:
        for suffix in (".turnstile", ".lock"):
            Path(os.environ["BIPED_GAIT_TEST_LOCK"] + suffix).unlink(missing_ok=True)
        shutil.rmtree(os.environ["BIPED_GAIT_CACHE"], ignore_errors=True)
