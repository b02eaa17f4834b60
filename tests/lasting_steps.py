"""What every walked step of a double support that lasts must show (tests/test_lasting_walk.py,
tests/test_lasting_hips.py): no fall, the step lasting T + d, the double support's samples with both
feet on the ground and pressing, every torque within the joints' 200 N m."""

from __future__ import annotations

import numpy as np
import pytest

from biped_gait.core.walking.events import DOUBLE_SUPPORT

EFFORT_LIMIT = 200.0  # N m: the joint table's, at which the walk's feedback is clipped


def check_lasting_step(k: int, outcome, step_duration: float, duration: float, rate: float) -> None:
    """Step ``k``'s ``outcome`` (``Walker.walk_step``) for a cycle of T + d = ``step_duration`` s
    with a double support of ``duration`` s, sampled at ``rate`` per second."""
    assert not outcome.fall, f"step {k}: {outcome.fall}"
    assert outcome.touchdown.t_step == pytest.approx(step_duration, abs=0.01)
    double = [s for s in outcome.samples if s.phase == DOUBLE_SUPPORT]
    assert len(double) >= round(duration * rate) - 1
    for sample in double:
        assert len(sample.feet) == 2
        assert np.all(sample.forces[:, 2] > 0.0)
        assert np.max(np.abs(sample.torque)) <= EFFORT_LIMIT + 1e-9
