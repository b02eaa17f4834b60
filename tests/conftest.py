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

from biped_gait.bvp import locked_rotation
from biped_gait.gait import GaitPlanner, GaitRequest
from biped_gait.impulses import ImpactProblem

DEFAULT_REQUEST = GaitRequest(step_length=0.45, period=0.45, arm_amplitude=math.radians(23.5), mode="normal")


@pytest.fixture(scope="session")
def planner() -> GaitPlanner:
    return GaitPlanner()


@pytest.fixture(scope="session")
def default_gait(planner):
    return planner.plan(DEFAULT_REQUEST)


def impact_problem(planner: GaitPlanner, result) -> ImpactProblem:
    """Rebuild eqs. (6)-(10) for a solved gait from its reported velocities."""
    bm = planner.model
    q_t = np.array(result.qT)
    j1, j2 = bm.tip_jacobians(q_t)
    return ImpactProblem(
        bm.mass_matrix(q_t), j1, j2, np.array(result.Xd_b), np.array(result.Xd_a), locked_rotation(bm, q_t)
    )
