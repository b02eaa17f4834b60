"""The double support that lasts, walked (docs/model.md section 14.1): at the swing foot's
touchdown, I^- and the passive impact with both feet held (``HeldTouchdown``, instantaneous); then
d seconds with both feet on the ground, the closed chain driven by the planned torques and the
feedback that tracks the plan (``LastingDoubleSupport``, ``held_support``); at lift-off I^+, chosen
as the impulsive double support chooses its impulses, towards the next step re-aimed from the
actual state (``reaim``), and the leg exchange.

**I^- at the touchdown.** The plan's landing is soft: its held impact's impulses are zero. Off the
plan by the walk's errors (the re-aimed single support reaches q_T, not the plan's velocity), the
planned I^- could leave one of them pulling, and the phase would start off its plan. The walk
takes the I^- whose held impact presses both feet within their friction pyramids and starts the
phase nearest the plan's velocity (a linear program by HiGHS): the seven joint impulses set all
of it but the roll about the feet line, which no impulse changes. None is a fall, with the reason.

A gait's orbit carries its double support to track (``orbit.PlannedOrbit.double_support``): the
single support's reset goes to ``HeldTouchdown`` when the step's aim has one, else to its own next
phase (the impulsive double support). Units SI, rad; times in the step.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import linprog

from ...dynamics.closed_chain import ClosedChain, HeldImpact
from ...dynamics.impulses import pyramid
from ..engines.engine import Motion
from ..events import DOUBLE_SUPPORT, Fall
from ..held_support import HeldSupport
from ..state import WalkState
from .held import BothFeet, tracked
from .phase import End, Guard, Phase, Transition, WalkContext
from .reaim import LiftOff, impulsive_double_support

PRESS_TOLERANCE = 1e-9  # N s: a held impulse this close to the pyramid's faces is on them (HiGHS's feasibility)
# The lift-off's re-aim starts from the tracked phase's error (a few tenths of a mrad), which the
# ballistic step amplifies about 150-fold; its chord steps converge linearly (a factor of 5 to 50
# each), so from there they need up to about 15 where the impulsive walk's touchdowns need 7.
LIFT_OFF_REAIM_STEPS = 20
IMPULSE_WEIGHT = 1e-2  # rad/s per N m s: I^-'s distance from the plan's, against the landing's velocity's


@dataclass(frozen=True, eq=False)
class LastingTouchdown:
    """What a double support that lasts did (``events.Touchdown.double_support``): the touchdown's
    time (s in the walk), its distance to the plan's (max |(q, qd) - (q_T, qd_b)|, rad, rad/s), the
    double support's duration (s), the I^- applied and the plan's (N m s), and the held impact's
    impulses at the old and the new tip (N s, world axes of the step's model)."""

    t: float
    state_error: float
    duration: float
    i_minus: np.ndarray
    i_minus_planned: np.ndarray
    held_old: np.ndarray
    held_new: np.ndarray


def held_landing(plan: HeldSupport, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, HeldImpact]:
    """The I^- (N m s) whose held impact at the touchdown (``q``, ``qd``: the single support's
    pre-impact state) starts the double support nearest the plan's start (least sum |qd+ - qd*(0)|,
    rad/s, then least sum |I^- - I^-*| by a hundredth as much), pressing both feet within the
    parameter set's friction pyramid; and that impact (module docstring). ``Fall`` if none presses."""
    chain = plan.chain
    m = chain.mass_matrix(q)[np.ix_(chain.at, chain.at)]
    jump = np.linalg.solve(m, chain.selection)  # d qd / d I^-, the old tip held

    def landing(i_minus: np.ndarray) -> np.ndarray:
        held = chain.impact(q, qd + jump @ i_minus)
        return np.concatenate([held.old[:3], held.new[:3], held.qd])

    na, n = len(plan.i_minus), len(qd)
    base = landing(np.zeros(na))
    linear = np.column_stack([landing(e) - base for e in np.eye(na)])  # the impact is linear in the velocity
    rows = np.vstack([[0.0, 0.0, -1.0], pyramid(chain.bm.params.friction)])
    faces = np.kron(np.eye(2), rows)  # both tips: pressing, within the pyramid
    impulses, velocity = linear[:6], linear[6:]
    # Unknowns [I^-, s (na), r (n)]: least sum r + sum s / 100 with r >= |qd+ - qd*|, s >= |I^- - I^-*|.
    eye_a, eye_n = np.eye(na), np.eye(n)
    zero_an, zero_na = np.zeros((na, n)), np.zeros((n, na))
    a_ub = np.block([[faces @ impulses, np.zeros((len(faces), na + n))],
                     [eye_a, -eye_a, zero_an], [-eye_a, -eye_a, zero_an],
                     [velocity, zero_na, -eye_n], [-velocity, zero_na, -eye_n]])
    gap = plan.qd[0] - base[6:]
    b_ub = np.concatenate([-faces @ base[:6] + PRESS_TOLERANCE, plan.i_minus, -plan.i_minus, gap, -gap])
    cost = np.concatenate([np.zeros(na), np.full(na, IMPULSE_WEIGHT), np.ones(n)])
    result = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * (2 * na + n), method="highs")
    if result.status != 0:
        planned = chain.impact(q, qd + jump @ plan.i_minus)
        raise Fall(f"no I^- lands both feet pressing within the friction cone: with the plan's the held impact's "
                   f"vertical impulses are {planned.old[2]:.3g} and {planned.new[2]:.3g} N s ({result.message})")
    i_minus = result.x[:na]
    return i_minus, chain.impact(q, qd + jump @ i_minus)


def held_touchdown(plan: HeldSupport, state: WalkState, end: End) -> tuple[LastingTouchdown, HeldImpact]:
    """The touchdown ``end`` of ``state``'s step onto the double support ``plan``: the I^- that lands
    it (``held_landing``) and what it did, and the held impact."""
    i_minus, held = held_landing(plan, end.q, end.qd)
    report = LastingTouchdown(state.t + end.t, state.aim.orbit.touchdown_error(end.q, end.qd), plan.duration, i_minus,
                              plan.i_minus, held.old, held.new)
    return report, held


@dataclass(frozen=True, eq=False)
class HeldTouchdown(Phase):
    """The touchdown onto a double support that lasts: I^- and the held impact (module docstring);
    then the double support, and after it ``after`` (the walk's single support)."""

    after: Phase
    kind = DOUBLE_SUPPORT

    def motion(self, ctx: WalkContext, state: WalkState) -> None:
        return None

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        plan = state.aim.orbit.double_support
        report, held = held_touchdown(plan, state, end)
        return Transition(LastingDoubleSupport(plan, end.t, report, self.after), state.moved(end.t, end.q, held.qd))


@dataclass(frozen=True, eq=False)
class LastingDoubleSupport(BothFeet):
    """Both feet on the ground for the ``plan``'s duration from ``start`` (s in the step), its
    torques and the feedback tracking it; then I^+ and the leg exchange (module docstring), and
    ``after``. ``report``: what its touchdown did."""

    plan: HeldSupport
    start: float
    report: LastingTouchdown
    after: Phase
    kind = DOUBLE_SUPPORT

    @property
    def chain(self) -> ClosedChain:
        return self.plan.chain

    def motion(self, ctx: WalkContext, state: WalkState) -> Motion:
        return tracked(self.plan, self.start)

    def guard(self, ctx: WalkContext, state: WalkState) -> Guard:
        return Guard(at=self.start + self.plan.duration)

    def reset(self, ctx: WalkContext, state: WalkState, end: End) -> Transition:
        """I^+ at lift-off: the impulses of the re-aimed double support from the actual state (its
        I^- and I^+, at one instant, are one joint impulse), reported as the step's I^+ beside the
        touchdown's I^-; the step's effort their sum |I| (the torques' integral is in the samples).
        With legs of pitch joints only the new tip's sideways drift (``ClosedChain.lateral_drift``)
        is handed to the old one, which leaves: the new foot is at rest, as its impulses need."""
        following, lift_off = impulsive_double_support(ctx, state, end.q, end.qd, end.t,
                                                       LiftOff(self.chain.lateral_drift(end.q, end.qd), LIFT_OFF_REAIM_STEPS))
        report = self.report
        i_plus = lift_off.i_minus + lift_off.i_plus
        touchdown = replace(lift_off, i_minus=report.i_minus, i_plus=i_plus,
                            W=float(np.abs(report.i_minus).sum() + np.abs(i_plus).sum()),
                            state_error=report.state_error, double_support=report)
        return Transition(self.after, following, (touchdown,))
