"""Shared fixtures: one planner per parameter set and the default gait, solved once."""

from __future__ import annotations

import math
import os
import random

# Every ROS process of the test session (this one and the nodes it starts) keeps DDS discovery
# on this machine and uses a domain of its own, so parallel sessions do not see each other.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", str(random.SystemRandom().randint(1, 100)))

import numpy as np
import pytest

from biped_gait.core.gait.planner import GaitPlanner, GaitRequest
from biped_gait.core.dynamics.impulses import ImpactLayout, ImpactProblem

DEFAULT_REQUEST = GaitRequest(step_length=0.45, period=0.45, arm_amplitude=math.radians(23.5), mode="normal")


@pytest.fixture(scope="session")
def planner() -> GaitPlanner:
    return GaitPlanner()


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
