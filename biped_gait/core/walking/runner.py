"""The runner of a walk (docs/model.md section 8): the one loop that takes the walk's phases one
after another, has the engine integrate each, and owns the samples, the pushes and the falls.

As SciPy's ``solve_ivp`` drives its solvers (they only step; the driver samples the dense output
and locates the events), the runner drives an engine (``engines``) through the walk's phases
(``phases``): it begins each phase in the engine with the phase's motion, advances it one
integration step at a time until the phase's guard fires, cutting the steps at the pushes (each a
velocity jump, ``push``) and collecting the publishing instants k / rate of the walk, which the
engine's output gives at the phase's end (one call: the hybrid engine's interpolant, MuJoCo's
records); the phase gives the contact forces at them (unless the engine measured them) and the
lowest link, the phase's motion the joint torques that act (``Motion.torques``), and the first sample that falls (a held foot's vertical reaction not positive or
its force out of the friction cone; where the engine measures the feet's tips, one lifted or slid
more than ``LIFT_LIMIT``, ``SLIP_LIMIT``; a link below the ground after the first 5 % of the step)
ends the walk. Then the phase's reset returns the transition, a value: the next phase, the
walk's state, the events (a touchdown ends a step).

Between steps the runner can be given pushes on the trunk at times in the next step (``push``) and
another gait to aim at (``retarget``: the next step is a transition step, transitions.py).

Everything is in the model's coordinates (stance leg 1 on the right); ``stance_side`` says
which physical foot that is, and ``stance_foot`` where it is in the world (m). Units SI, rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import DEFAULTS, Settings
from .engines.engine import Engine, Motion
from .engines.hybrid import HybridEngine
from .events import Fall, Sample, StepOutcome, Touchdown
from .feedback import Feedback
from .orbit import Cycle, PlannedOrbit, as_cycle
from .phases.impulsive import SingleSupport
from .phases.phase import AFTER, AT, TIME_TOLERANCE, TOUCHDOWN, End, Phase, WalkContext
from .phases.standing import Standing
from .phases.starting import starting
from .phases.stopping import StopTouchdown
from .push import AppliedPush, Push, TrunkPush
from .state import WalkState
from .kept import SETTLED, KeptPlan, Unsettled, unsettled

LINKS_CHECKED_AFTER = 0.05  # of the aimed period: a link below the ground is a fall from then on (not at the toe-off)
SLIP_LIMIT = LIFT_LIMIT = 1e-3
"""m: a foot whose tip an engine measures (MuJoCo's contacts) may unload for an instant, lift and
slide a little, as a real foot does; one that slid farther than ``SLIP_LIMIT`` from where it was
put down, or rose higher than ``LIFT_LIMIT``, has fallen (standing, MuJoCo's feet creep 1 um in
5 s)."""


def prepare_walking() -> None:
    """Load what walking needs once and a plan does not: SciPy's root finder, which the touchdown
    guard imports on first use (``hybrid._root``; a few tenths of a second). Called when a
    ``Walker`` is made, and by a process that walks at start-up (the simulator node), so that
    its first walk starts at once."""
    import scipy.optimize  # noqa: F401


@dataclass(frozen=True, eq=False)
class PhaseRun:
    """One phase as the runner walked it: its samples, the pushes that acted in it, the events its
    reset returned, and the reason the robot fell ('' if it did not)."""

    samples: list[Sample]
    pushes: tuple[AppliedPush, ...]
    events: tuple = ()
    fall: str = ""


class Walker:
    """Walks the gait of ``orbit`` (one periodic step, or the steps of a stride, ``Cycle``) from its
    start, phase after phase (module docstring).

    ``rate``: samples per second of simulated time; ``reaim``, ``momentum_rate``: the feedback
    (``feedback.Feedback``: re-solve each step's BVP from the actual state, else aim at the plan's
    velocity; steer the momentum about the feet line back to the plan's, its error contracting by
    this factor per step, docs/model.md section 8.7; None: the duration-only re-aim of section
    8.5); ``settings.walk_steps``: RK8 steps per period T; ``engine``: what integrates the phases
    (None: the planner's own model, ``engines.hybrid.HybridEngine``); ``phase``: the walk's first
    phase, whose resets give the others (None: the ballistic single support with impulsive double
    supports, ``phases.impulsive``)."""

    def __init__(self, hybrid: HybridStep, orbit: PlannedOrbit | Cycle, rate: float, reaim: bool = True,
                 settings: Settings = DEFAULTS, momentum_rate: float | None = None, engine: Engine | None = None,
                 phase: Phase | None = None) -> None:
        if not rate > 0:
            raise ValueError(f"publishing rate must be positive, got {rate}")
        prepare_walking()
        feedback = Feedback(hybrid, settings, reaim, momentum_rate)
        self.rate = rate
        self.engine = engine if engine is not None else HybridEngine(hybrid)
        self.context = WalkContext(hybrid, feedback, self.engine, TrunkPush(hybrid.bm))
        self.phase = phase if phase is not None else SingleSupport()
        aim = feedback.aim(as_cycle(orbit))
        q, qd = self.phase.first_state(aim)
        self.state = WalkState(np.array(q), np.array(qd), aim,
                               stance_foot=np.array([0.0, -hybrid.bm.params.hip_half_width, 0.0]))
        self.sample_index = 0  # the next sample is at sample_index / rate in the walk (s)
        self._workspace = self.engine.workspace()
        self._pushes: list[Push] = []  # to act in the current step, by time

    @property
    def hybrid(self) -> HybridStep:
        return self.context.hybrid

    @property
    def bm(self):
        return self.context.hybrid.bm

    @property
    def grid(self) -> int:
        """RK8 steps per planned period."""
        return self.context.grid

    @property
    def orbit(self) -> PlannedOrbit:
        """The plan the current step aims at."""
        return self.state.aim.orbit

    @property
    def period(self) -> float:
        """The current step's planned duration (s)."""
        return self.state.aim.period

    @property
    def cycle(self) -> Cycle:
        """The steps of the gait walked (one, or a stride's two)."""
        return self.state.aim.cycle

    def retarget(self, orbit: PlannedOrbit | Cycle) -> None:
        """Aim the next step at ``orbit`` (another gait, or the steps of a stride: its step on the
        next stance foot, A on the right, B on the left): from the current step's touchdown on, the
        re-aim steers to it and touchdowns are compared with it (a transition step, docs/model.md
        section 8.8)."""
        cycle = as_cycle(orbit)
        if not all(o.converged for o in cycle):
            raise ValueError("cannot walk a plan that did not converge")
        self.state = replace(self.state, aim=self.state.aim.retargeted(cycle))

    def stop(self, stop: KeptPlan) -> None:
        """End the walk standing: the current step's touchdown goes onto ``stop``'s double support
        and from its end the robot stands (``phases.stopping``). ``ValueError`` with the reason if
        the current step cannot: it is under way or not a ballistic single support (the MuJoCo
        walk's), it aims at another gait than the stop's, another gait is to be aimed at next, or it
        starts farther from its gait's start than ``kept.SETTLED`` (``kept.Unsettled``: a walk still
        settling after a push, a few steps more)."""
        phase, aim, s = self.phase, self.state.aim, self.state
        if type(phase) is not SingleSupport or s.t_step > 0.0:
            raise ValueError("a stop begins with a step of the hybrid engine's ballistic walk, before it starts")
        why = stop.why_not(aim.orbit) or ("the walk is aimed at another gait from this step's touchdown"
                                          if aim.pending is not None else "")
        if why:
            raise ValueError(f"cannot stop at this step: {why}")
        off = unsettled(s.q, s.qd, aim.orbit)
        if off > SETTLED:
            raise Unsettled(f"cannot stop at this step: the step starts {off:.2g} off its gait's start, more than the "
                            f"{SETTLED:g} it stops from")
        self.phase = SingleSupport(StopTouchdown(stop.plan, Standing(stop.balance)))

    def start(self, start: KeptPlan) -> None:
        """Set off from standing onto the walk's gait: the start's double support from now, then I^+
        onto the gait's next step and its single support (``phases.starting``). ``ValueError`` with
        the reason if the walk is not standing, ``start`` is not planned with the gait it is aimed
        at (or another gait is to be aimed at next), or it stands farther than ``kept.SETTLED`` from
        the start's posture at rest (``kept.Unsettled``)."""
        s = self.state
        if not isinstance(self.phase, Standing):
            raise ValueError("a start begins from standing")
        why = start.why_not(s.aim.orbit) or ("the walk is aimed at another gait" if s.aim.pending is not None else "")
        if why:
            raise ValueError(f"cannot start: {why}")
        phase = starting(start.plan, s)
        if phase.report.state_error > SETTLED:
            raise Unsettled(f"cannot start: the robot stands {phase.report.state_error:.2g} off the start's posture at "
                            f"rest, more than the {SETTLED:g} it starts from")
        self.phase = phase

    def shove(self, delta_qd: np.ndarray) -> None:
        """Add ``delta_qd`` (rad/s, model coordinates) to the velocity the current phase starts with."""
        self.state = replace(self.state, qd=self.state.qd + np.asarray(delta_qd, float))

    def push(self, push: Push) -> None:
        """Let ``push`` act in the current step: the integration is cut at its time, the trunk
        impulse's velocity jump is added, and it goes on from there; a push the step does not
        reach acts on the pre-impact state at its touchdown (docs/model.md section 8.6)."""
        self._pushes = sorted([*self._pushes, push], key=lambda p: p.time_in_step)

    def walk_step(self) -> StepOutcome:
        """Walk phases until one's reset reports an event (a touchdown: the step's end) or the robot
        falls: their samples, the touchdown or the fall, the pushes."""
        samples: list[Sample] = []
        pushes: tuple[AppliedPush, ...] = ()
        while True:
            run = self.run_phase()
            samples += run.samples
            pushes += run.pushes
            if run.fall:
                return StepOutcome(samples, None, run.fall, pushes)
            if run.events:
                touchdown = next((event for event in run.events if isinstance(event, Touchdown)), None)
                return StepOutcome(samples, touchdown, pushes=pushes)

    def run_phase(self) -> PhaseRun:
        """Walk the current phase to its end (module docstring): its samples, pushes, the events of
        its reset, or the fall; the runner's phase and state become the transition's."""
        ctx, engine, ws = self.context, self.engine, self._workspace
        phase, s = self.phase, self.state
        motion = phase.motion(ctx, s)
        if motion is None:  # instantaneous: its reset at once
            return self._reset(phase, End(AT, s.t_step, s.q, s.qd), [], [])
        guard = phase.guard(ctx, s)
        engine.begin(ws, motion, s.t, s.t_step, s.q, s.qd)
        t, segments, taus, jumps, applied = s.t_step, [], [], [], []
        end, fall = None, ""
        if t >= guard.after - TIME_TOLERANCE:
            end = End(AFTER, t, s.q, s.qd)
        try:
            while end is None:
                if t >= guard.deadline:
                    fall = guard.overdue
                    break
                if self._pushes and self._pushes[0].time_in_step <= t + TIME_TOLERANCE:
                    phase = phase.pushed(ctx, s, t, *self._apply_pushes(phase, t, t, applied))
                    guard = phase.guard(ctx, s)
                    jumps.append(t)
                t_stop = min(guard.at, self._pushes[0].time_in_step if self._pushes else math.inf)
                segment = engine.advance(ws, motion, t_stop, guard.touchdown_after)
                segments.append(segment)
                t_end = segment.t
                # The instants k / rate of the walk in the step up to its end: an instant at a
                # touchdown opens the next phase (the state after the impact), one at another end
                # of a phase (the state continuous) closes this one.
                while (tau := (self.sample_index + len(taus)) / self.rate - s.t) < t_end - TIME_TOLERANCE or (
                    not segment.touchdown and tau <= t_end
                ):
                    taus.append(tau)
                t = t_end
                if segment.touchdown:
                    end = End(TOUCHDOWN, t, *engine.state(ws))
                elif t >= guard.at - TIME_TOLERANCE:
                    end = End(AT, t, *engine.state(ws))
                elif t >= guard.after - TIME_TOLERANCE:
                    end = End(AFTER, t, *engine.state(ws))
        except Fall as exc:  # a phase that plans again after a push found it cannot
            fall = str(exc)
        samples, sample_fall = self._samples(phase, motion, s, segments, taus, jumps)
        if sample_fall or fall:
            self._pushes = []
            return PhaseRun(samples, tuple(applied), fall=sample_fall or fall)
        if end.event == TOUCHDOWN and self._pushes:  # pushes later than the touchdown act on it
            end = End(TOUCHDOWN, end.t, *self._apply_pushes(phase, end.t, math.inf, applied))
        return self._reset(phase, end, samples, applied)

    def _reset(self, phase: Phase, end: End, samples: list[Sample], applied: list[AppliedPush]) -> PhaseRun:
        """The transition out of ``phase``: the runner's phase and state become its own."""
        try:
            transition = phase.reset(self.context, self.state, end)
        except Fall as exc:
            self._pushes = []
            return PhaseRun(samples, tuple(applied), fall=str(exc))
        self.phase, self.state = transition.phase, transition.state
        return PhaseRun(samples, tuple(applied), transition.events)

    def _apply_pushes(self, phase: Phase, t: float, due: float,
                      applied: list[AppliedPush]) -> tuple[np.ndarray, np.ndarray]:
        """Apply the pushes due by ``due`` (s in the step) at ``t`` to the engine's state: each
        one's velocity jump, reported; the state after them."""
        ctx, engine, ws, s = self.context, self.engine, self._workspace, self.state
        q, qd = engine.state(ws)
        while self._pushes and self._pushes[0].time_in_step <= due + TIME_TOLERANCE:
            push = self._pushes.pop(0)
            jump = phase.push_jump(ctx, s, q, push.impulse)
            applied.append(AppliedPush(s.step, s.stance_side, s.t + t, t, push.impulse, jump))
            qd = qd + jump
        engine.set_velocity(ws, qd)
        return q, qd

    def _samples(self, phase: Phase, motion: Motion, s: WalkState, segments: list, taus: list[float],
                 jumps: list[float]) -> tuple[list[Sample], str]:
        """The samples at ``taus`` (s in the step) in the phase's ``segments`` (integrated with
        ``motion``: its torques), evaluated in one call, up to the first that falls; and the fall's
        reason ('' for none)."""
        samples: list[Sample] = []
        if not taus:
            return samples, ""
        ctx = self.context
        q, qd, measured = self.engine.sample(self._workspace, segments, taus, jumps)
        torques = motion.torques(q, qd, np.array(taus))
        forces, lowest = phase.evaluate(ctx, q, qd, torques)
        moved = None
        if measured is not None:
            forces, moved = measured.forces, measured.moved
        feet = phase.feet(s)
        friction = min(self.engine.contact_friction, phase.friction)
        checked_after = LINKS_CHECKED_AFTER * s.aim.period
        for k, tau in enumerate(taus):
            samples.append(Sample(s.t + tau, tau, q[k], qd[k], forces[k], torques[k], feet, s.step, phase.kind))
            self.sample_index += 1
            fall = self._fall(samples[-1], float(lowest[k]), checked_after, friction,
                              None if moved is None else moved[k])
            if fall:
                return samples, fall
        return samples, ""

    @staticmethod
    def _fall(sample: Sample, lowest_link: float, checked_after: float, mu: float,
              moved: np.ndarray | None) -> str:
        """Why ``sample`` is a fall ('' if it is not); ``lowest_link``: the height (m) of its
        lowest knee, hip, shoulder or hand, checked after ``checked_after`` s in the step; ``mu``:
        the friction coefficient a held foot's contact force must keep within (inf: none checked);
        ``moved``: how far each foot's tip has moved from where it was put down (feet x 3, m,
        measured by the engine, whose contacts keep their forces in their cone: a foot slides
        instead; None: held there, its vertical reaction must then stay positive, its force in the
        cone)."""
        several = len(sample.feet) > 1
        if moved is None:
            for foot, force in zip(sample.feet, sample.forces):
                if not force[2] > 0.0:
                    at = f" at the {foot.side} foot" if several else ""
                    return f"vertical ground reaction{at} not positive ({force[2]:.3g} N) at t = {sample.t:.4f} s"
        else:
            for foot, (dx, dy, dz) in zip(sample.feet, moved):
                if dz > LIFT_LIMIT:
                    return f"the {foot.side} foot lifted {dz * 1e3:.1f} mm at t = {sample.t:.4f} s"
                if math.hypot(dx, dy) > SLIP_LIMIT:
                    return f"the {foot.side} foot slid {math.hypot(dx, dy) * 1e3:.1f} mm at t = {sample.t:.4f} s"
        if sample.t_step > checked_after and lowest_link < 0.0:
            return f"a link went below the ground at t = {sample.t:.4f} s"
        if math.isfinite(mu) and moved is None:
            for foot, (fx, fy, fz, _) in zip(sample.feet, sample.forces):
                if math.hypot(fx, fy) > mu * fz:
                    return (f"the {'stance' if foot is sample.feet[0] else foot.side} foot slips at t = {sample.t:.4f} s: "
                            f"|F_xy| / F_z = {math.hypot(fx, fy) / fz:.3f} > mu = {mu:g}")
        return ""
