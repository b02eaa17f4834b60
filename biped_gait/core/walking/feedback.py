"""The walk's feedback: the per-step re-aim of the next step from the actual touchdown, with
momentum steering or without (docs/model.md sections 8.5, 8.7), and the plan it aims at, moved on
at each touchdown (a stride's next step, or another gait: a transition step, section 8.8).

Off the planned orbit the plan's post-impact velocity is not exactly reachable: the angular
momentum about the foot-to-foot line is conserved through the double support. The ballistic gait
is open-loop unstable (a touchdown error grows about 150-fold per step), so by default the walk
re-aims each step: it re-solves the next step's boundary-value problem from the actual
configuration after the leg exchange to the planned touchdown configuration, with the next step's
DURATION as the free tenth unknown (the one quantity the impulses cannot set, that momentum, is
regulated by how long gravity acts on it), under the current impact's momentum closure. With
``momentum_rate`` the re-aim also steers that momentum back to the plan's (``steering``: the next
touchdown's trunk pitch freed).

Units SI, rad.
"""

from __future__ import annotations

import numpy as np

from ..dynamics import newton
from ..dynamics.hybrid import HybridStep, ImpactMap
from ..dynamics.settings import DEFAULTS, Settings
from ..gait.configurations import pitch_direction
from .events import Fall
from .orbit import Cycle
from .state import Aim, AimedStep
from .steering import MomentumSteering, SteeringFailed, reference


class Feedback:
    """The re-aim of ``hybrid``'s walk on the grid of ``settings.walk_steps`` RK8 steps per period:
    ``reaim`` (else the walk aims at the plan's velocity made reachable), ``momentum_rate`` (steer
    the momentum about the feet line back to the plan's, its error contracting by this factor per
    step; None: the duration-only re-aim)."""

    def __init__(self, hybrid: HybridStep, settings: Settings = DEFAULTS, reaim: bool = True,
                 momentum_rate: float | None = None) -> None:
        if momentum_rate is not None and not reaim:
            raise ValueError("steering the momentum is part of the re-aim: it needs reaim")
        self.hybrid, self.bm, self.settings = hybrid, hybrid.bm, settings
        self.reaim, self.momentum_rate = reaim, momentum_rate
        self.grid = settings.walk_steps
        self.step_flow = hybrid.flow(self.grid)

    def aim(self, cycle: Cycle, transition: np.ndarray | None = None, index: int = 0) -> Aim:
        """The aim at step ``index`` of ``cycle``, each of its steps prepared for the re-aim: the
        momentum steering towards it (its first one a transition from another gait, whose last
        solution was ``transition`` away from that gait's), or d q(T) / d qd(0) on it (the plain
        re-aim's chord Jacobian)."""
        steps = []
        for k, orbit in enumerate(cycle):
            if not orbit.converged:
                raise ValueError("cannot walk a plan that did not converge")
            q0, q_t, qd_a, qd_b = (np.asarray(orbit.q0), np.asarray(orbit.q_t), np.asarray(orbit.qd_a),
                                   np.asarray(orbit.qd_b))
            if self.momentum_rate is not None:
                ref = reference(self.hybrid, self.step_flow, q0, q_t, qd_a, qd_b, orbit.period,
                                *self._stride_pitches(cycle, k))
                coarse = self.hybrid.flow(self.settings.coarse_steps) if self.settings.coarse_steps < self.grid else None
                steps.append(AimedStep(orbit, steering=MomentumSteering(self.hybrid, self.step_flow, ref, self.momentum_rate,
                                                                        coarse, transition if k == 0 else None)))
            elif self.reaim:
                n = self.bm.nq
                seeds = np.vstack([np.zeros((n, n)), np.eye(n)])
                steps.append(AimedStep(orbit, chord=self.step_flow.propagate(q0, qd_a, orbit.period, seeds).sens[:n]))
            else:
                steps.append(AimedStep(orbit))
        return Aim(tuple(steps), index, cycle[index].period)

    def _stride_pitches(self, cycle: Cycle, k: int) -> tuple:
        """What the steering reference of step ``k`` of ``cycle`` needs beyond a periodic gait's:
        nothing for a straight gait; in a stride, e_theta at its touchdown and the step before's
        touchdown (configuration, velocity, e_theta), which starts it."""
        if len(cycle) == 1:
            return ()
        previous = cycle[k - 1]
        q_p = np.asarray(previous.q_t)
        return (pitch_direction(self.bm, np.asarray(cycle[k].q_t)),
                (q_p, np.asarray(previous.qd_b), pitch_direction(self.bm, q_p)))

    def advanced(self, aim: Aim, next_side: str) -> Aim:
        """The aim of the step after ``aim``'s, which stands on ``next_side``: the gait it was
        retargeted to (its step on that foot: A on the right, B on the left), a stride's next step,
        or the same periodic step."""
        if aim.pending is not None:
            steering = aim.step.steering
            return self.aim(aim.pending, steering.offset if steering is not None else None,
                            0 if len(aim.pending) == 1 or next_side == "right" else 1)
        if len(aim.steps) > 1:
            index = (aim.index + 1) % len(aim.steps)
            return Aim(aim.steps, index, aim.steps[index].orbit.period)
        return aim

    def reaim_velocity(self, aim: Aim, q_start: np.ndarray, impact: ImpactMap, xd_b: np.ndarray,
                       foot_line_moment: float, again: bool = False, steps: int | None = None) -> tuple[np.ndarray, float]:
        """The next step's initial velocity (its own coordinates, rad/s) and duration (s): the
        flow from ``q_start`` reaches ``aim``'s touchdown configuration q_T exactly, and the
        velocity is reachable through this double support (the momentum about the feet line is
        kept, up to the ``foot_line_moment`` (kg m^2/s) the ground's spin moments change).
        ``aim``: the next step's, its ``next_period`` the warm start; ``again``: the same touchdown
        as the last re-aim, with another ``foot_line_moment`` (a closure round); ``steps``: the chord
        steps allowed (None: ``settings.reaim_steps``).

        Chord steps with the planned orbit's Jacobian: off the orbit by a numerical error
        only, they converge to rounding level in one or two steps. With momentum steering, the
        steered re-aim (``steering``) instead. ``Fall`` if it fails.
        """
        step = aim.step
        if step.steering is not None:
            try:
                q_pre = self.hybrid.exchange.configuration(q_start)  # the exchange is an involution
                v, period, _ = step.steering.solve(q_pre, impact, xd_b, aim.next_period, foot_line_moment, again)
            except SteeringFailed as exc:
                raise Fall(str(exc)) from None
            return v, period
        orbit = aim.orbit
        q_t, qd_b = np.asarray(orbit.q_t), np.asarray(orbit.qd_b)
        gain, _ = impact.closure_gradients()  # d(momentum after)/d(qd_next)
        target_momentum = float(impact.momentum_row @ xd_b) - foot_line_moment
        n = self.bm.nq
        jac = np.zeros((n + 1, n + 1))
        jac[:n, :n], jac[:n, n], jac[n, :n] = step.chord, qd_b, gain

        def residual(x: np.ndarray):
            v, duration = x[:n], x[n]
            if not duration > 0:
                return np.full(n + 1, np.nan), None
            with np.errstate(over="ignore", invalid="ignore"):
                run = self.step_flow.propagate(q_start, v, duration)
            return np.append(run.q - q_t, gain @ v - target_momentum), None

        x0 = np.append(np.asarray(orbit.qd_a), aim.next_period)
        result = newton.chord(residual, x0, jac, 1e-12, steps or self.settings.reaim_steps)
        if result.status == newton.DIVERGED:
            raise Fall("re-aiming the next step diverged: the state is too far from the plan")
        if not result.converged:
            raise Fall("re-aiming the next step did not converge: the state is too far from the plan")
        return result.x[:n], float(result.x[n])
