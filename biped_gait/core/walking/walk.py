"""Walking a planned gait step after step: a plan in, samples and events out (the core of the
simulator node; docs/model.md section 8).

Each step integrates the ballistic dynamics from the actual state (the hybrid step's flow, one
RK8 step of the walk's grid at a time), detects the swing foot's touchdown with the hybrid
step's guard (located on the quintic Hermite interpolant and landed on by an exact RK8 step),
evaluates the step's samples in one call (``samples.SampleEvaluator``; the first that falls ends
the walk), applies the double support with impulses recomputed by the LP from the actual
pre-impact state, and exchanges the legs (the reset).

Off the planned orbit the plan's post-impact velocity is not exactly reachable: the angular
momentum about the foot-to-foot line is conserved through the double support. Aiming at the
nearest reachable velocity (the plan's plus s z_d, z_d the locked rotation) is not enough to
walk: the ballistic gait is open-loop unstable (a touchdown error grows about 150-fold per
step), so by default (``reaim=True``) the walker re-aims each step. It re-solves the next
step's boundary-value problem from the actual configuration after the leg exchange to the
planned touchdown configuration, with the next step's DURATION as the free tenth unknown (the
one quantity the impulses cannot set, that momentum, is regulated by how long gravity acts on
it), under the current impact's momentum closure, so that the target is exactly reachable and
the next touchdown lands on the plan. It reports |s| for the plan's own velocity as the miss,
and how far the re-aimed velocity is from the plan's. That momentum is left to decay by
itself (1 % per step); with ``momentum_rate`` the re-aim also steers it back to the plan's
(``steering``: the next touchdown's trunk pitch freed).

Between steps the walker can be given a push on the trunk at a time in the next step
(``push``, core/walking/push.py: the step is split there) and another gait to aim at (``retarget``: the
next step is a transition step, core/walking/transitions.py).

Everything is in the model's coordinates (stance leg 1 on the right); ``stance_side`` says
which physical foot that is, and ``stance_foot`` where it is in the world (m). Units SI, rad.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np

from ..dynamics import newton
from ..gait.configurations import GaitMode, pitch_direction
from ..dynamics.flow import hermite_samples
from ..dynamics.hybrid import HybridStep, ImpactMap
from ..model.exchange import next_heading, other_side, world_axes
from ..dynamics.impulses import EffortOptions, friction_ratios, solve_impulses
from ..model.biped import BipedModel
from ..model.params import load_params
from .push import AppliedPush, Push, TrunkPush
from ..dynamics.settings import DEFAULTS, Settings
from .steering import MomentumSteering, SteeringFailed, reference
from .world import WorldPictures, WorldState, WorldView

CLOSURE_ROUNDS = 10  # re-aims per double support at most, with legs leaning (the planner's rounds)
ENGINES = ("hybrid", "mujoco")
"""How a walk's steps are integrated: ``hybrid``, the planner's own model (this module); ``mujoco``,
MuJoCo on the floating export with the double support as torque pulses (``mujoco_engine``)."""
PULSE_DURATION = 5e-3  # s: the double support's duration d with the MuJoCo engine


@dataclass(frozen=True)
class PlannedOrbit:
    """What a walk needs of a plan: the parameter set (name or file), the gait's L (m), T (s),
    alpha (rad), mode, effort, the boundary configurations q0 and q_t (rad), the velocities
    qd_a at the start and qd_b at the end of the step (rad/s), the plan's verdict, and how its
    impulses are chosen (friction cone, joint-rate bound, the effort's reading), what the
    ground's spin moments change of the momentum about the feet line in the double support that
    ends the step (kg m^2/s; zero but for legs leaning, docs/model.md section 5.2), the trunk
    pitch theta of its touchdown configuration (rad) and the radius of the circle it is a step
    of (m, signed; inf: straight)."""

    params: str
    step_length: float
    period: float
    arm_amplitude: float
    mode: GaitMode
    effort: str
    q0: np.ndarray
    q_t: np.ndarray
    qd_a: np.ndarray
    qd_b: np.ndarray
    converged: bool = True
    admissible: bool = True
    reasons: tuple[str, ...] = ()
    options: EffortOptions = EffortOptions()
    foot_line_moment: float = 0.0
    theta: float = math.nan
    turn_radius: float = math.inf

    @classmethod
    def of(cls, gait) -> "PlannedOrbit":
        """The orbit of a solved ``gait.Gait``."""
        ds = gait.double_support
        return cls(gait.problem.params, gait.step_length, gait.period, gait.arm_amplitude, gait.mode,
                   gait.problem.effort, gait.step.q0, gait.step.q_target, gait.step.qd_a, gait.step.qd_b,
                   gait.converged, gait.admissible, gait.reasons, gait.problem.impulse_options,
                   ds.foot_line_moment if ds is not None else 0.0, gait.theta, gait.problem.turn_radius)


class Fall(Exception):
    """The robot fell, or its next step cannot be made: the message says why."""


@dataclass(frozen=True)
class Sample:
    """The state at one publishing instant: time in the walk (s) and in the step, q, qd, the
    ground reaction [Fx, Fy, Fz, Mz] at the stance tip (N, N m), the step, its stance side and
    stance foot (m, world), and the robot in world terms (``Walk`` fills it)."""

    t: float
    t_step: float
    q: np.ndarray
    qd: np.ndarray
    grf: np.ndarray
    step: int = 0
    stance_side: str = "right"
    stance_foot: np.ndarray | None = None
    world: WorldState | None = None


@dataclass(frozen=True)
class StepSamples:
    """Samples of one step as ``Walk.batches`` yields them (all of the step's, or those on one
    side of a push): each ``Sample`` (without its ``world``), and the robot in world terms at
    their instants, one row each."""

    samples: list[Sample]
    world: WorldPictures

    @property
    def t(self) -> np.ndarray:
        """The samples' times in the walk (s)."""
        return np.array([sample.t for sample in self.samples])


@dataclass(frozen=True)
class Touchdown:
    """The end of one step: when, the double support applied, and the distance to the plan."""

    step: int
    t: float  # time in the walk (s)
    t_step: float  # duration of the step (s)
    i_minus: np.ndarray
    i_plus: np.ndarray
    W: float
    state_error: float  # max |(q, qd) at touchdown - the plan's (q_T, qd_b)| (rad, rad/s)
    velocity_miss: float  # |s|: how far the plan's post-impact velocity is from reachable (rad/s)
    correction: float  # max |re-aimed post-impact velocity - the plan's| (rad/s), 0 without re-aiming
    equation_residual: float
    next_stance_side: str = ""


@dataclass(frozen=True)
class Fell:
    """The walk ended with a fall in ``step``: at ``t`` (s in the walk), ``time_in_step`` (s)."""

    step: int
    t: float
    time_in_step: float
    stance_side: str
    reason: str


@dataclass(frozen=True)
class Finished:
    """The walk made all its steps: ``steps`` done by ``t`` (s); the next stance side."""

    steps: int
    t: float
    stance_side: str


@dataclass(frozen=True)
class CouldNotStart:
    """The plan cannot be walked (not converged, unknown parameters): the reason."""

    reason: str


@dataclass(frozen=True)
class StepOutcome:
    """One step: its samples, and its touchdown or the reason the robot fell; the pushes that
    acted in it."""

    samples: list[Sample]
    touchdown: Touchdown | None
    fall: str = ""
    pushes: tuple[AppliedPush, ...] = ()


@dataclass(frozen=True)
class WalkState:
    """Where the walker is: the model state at the start of the current step, which physical
    foot is the stance foot, that foot's world position (m), and the heading (rad) of the step's
    model frame (its axes are the world's turned by it about the vertical, then mirrored for a
    left stance)."""

    q: np.ndarray
    qd: np.ndarray
    step: int = 0
    t: float = 0.0
    stance_side: str = "right"
    stance_foot: np.ndarray = field(default_factory=lambda: np.array([0.0, -0.2, 0.0]))
    heading: float = 0.0

    @property
    def axes(self) -> np.ndarray:
        """The step's model axes in the world (3 x 3, ``world_axes``)."""
        return world_axes(self.stance_side, self.heading)


Cycle = tuple["PlannedOrbit", ...]
"""The steps a gait repeats: one for a straight gait, two (right foot, left foot) for a stride on a
circle, each in its own model coordinates."""


def as_cycle(orbit: "PlannedOrbit | Cycle") -> Cycle:
    """A gait's steps: ``orbit`` itself, or its steps."""
    return (orbit,) if isinstance(orbit, PlannedOrbit) else tuple(orbit)


def prepare_walking() -> None:
    """Load what walking needs once and a plan does not: SciPy's root finder, which the touchdown
    guard imports on first use (``hybrid._root``; a few tenths of a second). Called when a
    ``Walker`` is made, and by a process that walks at start-up (the simulator node), so that
    its first walk starts at once."""
    import scipy.optimize  # noqa: F401


class Walker:
    """Walks the gait of ``orbit`` (one periodic step, or the steps of a stride, ``Cycle``) with
    the dynamics of ``hybrid`` one step per ``walk_step``."""

    def __init__(self, hybrid: HybridStep, orbit: PlannedOrbit | Cycle, rate: float, reaim: bool = True,
                 settings: Settings = DEFAULTS, momentum_rate: float | None = None, engine=None) -> None:
        """``rate``: samples per second of simulated time; ``reaim``: re-solve each step's BVP
        from the actual state (else aim at the plan's velocity); ``momentum_rate``: steer the
        momentum about the feet line back to the plan's, its error contracting by this factor per
        step (``steering``, docs/model.md section 8.7; None: the duration-only re-aim of section
        8.5); ``settings.walk_steps``: RK8 steps per period T; ``engine``: what walks each step in
        place of the hybrid step (its ``walk_step(walker)``, e.g. ``mujoco_engine.MujocoEngine``:
        the walker's double support is then its feedback); None: the hybrid step."""
        if not rate > 0:
            raise ValueError(f"publishing rate must be positive, got {rate}")
        if momentum_rate is not None and not reaim:
            raise ValueError("steering the momentum is part of the re-aim: it needs reaim")
        prepare_walking()
        self.hybrid, self.bm, self.rate = hybrid, hybrid.bm, rate
        self.settings = settings
        self.grid = settings.walk_steps
        self.flow = hybrid.flow(1)  # one RK8 step per call: the walker owns the grid
        self.step_flow = hybrid.flow(self.grid)
        self.samples = hybrid.samples
        self.reaim, self.momentum_rate = reaim, momentum_rate
        self.steering: MomentumSteering | None = None
        self._cycle = self._prepared(as_cycle(orbit))
        self._aim_at(0)
        first = self._cycle[0][0]
        self.state = WalkState(np.array(first.q0), np.array(first.qd_a),
                               stance_foot=np.array([0.0, -self.bm.params.hip_half_width, 0.0]))
        self.sample_index = 0  # the next sample is at sample_index / rate in the walk (s)
        self.trunk_push = TrunkPush(self.bm)
        self._pushes: list[Push] = []  # to act in the current step, by time
        self._applied: list[AppliedPush] = []
        self._next_cycle: Cycle | None = None
        self.engine = engine

    def _prepared(self, cycle: Cycle, transition: np.ndarray | None = None) -> list[tuple]:
        """Each step of ``cycle`` with what its re-aim needs, computed once: the momentum steering
        towards it (its first one a transition from another gait, whose last solution was
        ``transition`` away from that gait's), or d q(T) / d qd(0) on it (the plain re-aim's
        chord Jacobian)."""
        out = []
        for k, orbit in enumerate(cycle):
            if not orbit.converged:
                raise ValueError("cannot walk a plan that did not converge")
            q0, q_t, qd_a, qd_b = (np.asarray(orbit.q0), np.asarray(orbit.q_t), np.asarray(orbit.qd_a),
                                   np.asarray(orbit.qd_b))
            aim = None
            if self.momentum_rate is not None:
                ref = reference(self.hybrid, self.step_flow, q0, q_t, qd_a, qd_b, orbit.period,
                                *self._stride_pitches(cycle, k))
                coarse = self.hybrid.flow(self.settings.coarse_steps) if self.settings.coarse_steps < self.grid else None
                aim = MomentumSteering(self.hybrid, self.step_flow, ref, self.momentum_rate, coarse,
                                       transition if k == 0 else None)
            elif self.reaim:
                n = self.bm.nq
                seeds = np.vstack([np.zeros((n, n)), np.eye(n)])
                aim = self.step_flow.propagate(q0, qd_a, orbit.period, seeds).sens[:n]
            out.append((orbit, aim))
        return out

    @property
    def cycle(self) -> Cycle:
        """The steps of the gait walked (one, or a stride's two)."""
        return tuple(orbit for orbit, _ in self._cycle)

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

    def _aim_at(self, index: int) -> None:
        """Make step ``index`` of the cycle the plan the walk aims at (and compares with)."""
        self._index = index
        orbit, aim = self._cycle[index]
        self.orbit, self.period = orbit, orbit.period
        self.guard = self.hybrid.guard(0.5 * orbit.period)
        self.q_t, self.qd_b, self.qd_a = np.asarray(orbit.q_t), np.asarray(orbit.qd_b), np.asarray(orbit.qd_a)
        self.next_period = orbit.period
        if self.momentum_rate is not None:
            self.steering = aim
        elif self.reaim:
            self._phi_qv = aim

    def retarget(self, orbit: PlannedOrbit | Cycle) -> None:
        """Aim the next step at ``orbit`` (another gait, or the steps of a stride: its step on the
        next stance foot, A on the right, B on the left): from the current step's touchdown on, the
        re-aim steers to it and touchdowns are compared with it (a transition step, docs/model.md
        section 8.8)."""
        cycle = as_cycle(orbit)
        if not all(o.converged for o in cycle):
            raise ValueError("cannot walk a plan that did not converge")
        self._next_cycle = cycle

    def shove(self, delta_qd: np.ndarray) -> None:
        """Add ``delta_qd`` (rad/s, model coordinates) to the velocity the current step starts with."""
        self.state = replace(self.state, qd=self.state.qd + np.asarray(delta_qd, float))

    def push(self, push: Push) -> None:
        """Let ``push`` act in the current step (the next ``walk_step``): the step is integrated
        to its time, the trunk impulse's velocity jump is added, and the integration goes on from
        there (docs/model.md section 8.6)."""
        self._pushes = sorted([*self._pushes, push], key=lambda p: p.time_in_step)

    def _until_push(self, t_step: float, h: float) -> float:
        """The length (s) of the integration step that starts at ``t_step``: ``h``, or less so
        that it ends at the next push."""
        if self._pushes and t_step < self._pushes[0].time_in_step < t_step + h:
            return self._pushes[0].time_in_step - t_step
        return h

    def _pushed(self, t_step: float, q: np.ndarray, qd: np.ndarray, due: float) -> np.ndarray:
        """``qd`` after the pushes due by ``due`` (s in the step) acted at (``t_step``, ``q``)."""
        s = self.state
        while self._pushes and self._pushes[0].time_in_step <= due + 1e-12:
            push = self._pushes.pop(0)
            jump = self.trunk_push.velocity_jump(q, push.impulse, s.axes)
            self._applied.append(AppliedPush(s.step, s.stance_side, s.t + t_step, t_step, push.impulse, jump))
            qd = qd + jump
        return qd

    def walk_step(self) -> StepOutcome:
        """Integrate the current step until touchdown (or 2 T), then evaluate its samples in one
        call; if none falls, apply the double support (or the ``engine``'s step)."""
        if self.engine is not None:
            return self.engine.walk_step(self)
        s = self.state
        h = self.period / self.grid
        t_step, q, qd = 0.0, s.q, s.qd
        limit = 2.0 * self.period
        runs: list[tuple[np.ndarray, ...]] = []  # the nodes (t, q, qd, qdd) of each integration step
        taus: list[float] = []
        touchdown = None
        while touchdown is None and t_step < limit:
            qd = self._pushed(t_step, q, qd, t_step)
            dt = self._until_push(t_step, h)
            run = self.flow.propagate(q, qd, dt, keep_nodes=True)
            nodes = (run.nodes[0] + t_step, *run.nodes[1:])
            runs.append(nodes)
            touchdown = self.guard.touchdown(nodes)
            t_end = t_step + dt if touchdown is None else touchdown
            # Samples at the instants k / rate of the walk that fall in [start, touchdown): the
            # touchdown instant itself opens the next step (post-impact state).
            while (tau := (self.sample_index + len(taus)) / self.rate - s.t) < t_end - 1e-12 or (
                touchdown is None and tau <= t_end
            ):
                taus.append(tau)
            t_step, q, qd = t_end, run.q, run.qd
        samples, fall = self._samples(runs, taus)
        pushes, self._applied = tuple(self._applied), []
        if fall:
            self._pushes = []
            return StepOutcome(samples, None, fall, pushes)
        if touchdown is None:
            self._pushes = []
            return StepOutcome(samples, None, f"the swing foot did not land within 2 T = {limit:.3f} s", pushes)
        t_start, q_start, qd_start = runs[-1][0][0], runs[-1][1][0], runs[-1][2][0]
        end = self.flow.propagate(q_start, qd_start, touchdown - t_start)
        qd_end = self._pushed(touchdown, end.q, end.qd, np.inf)  # pushes later than the touchdown act on it
        pushes, self._applied = pushes + tuple(self._applied), []
        try:
            return StepOutcome(samples, self._double_support(end.q, qd_end, touchdown), pushes=pushes)
        except Fall as exc:
            return StepOutcome(samples, None, str(exc), pushes)

    def _samples(self, runs: list[tuple[np.ndarray, ...]], taus: list[float]) -> tuple[list[Sample], str]:
        """The samples at times ``taus`` (s in the step) on the interpolant of the integration
        steps ``runs`` (each sample on the step whose closed interval holds it first), evaluated
        in one call, up to the first that falls; and the fall's reason ('' for none)."""
        s = self.state
        samples: list[Sample] = []
        if not taus:
            return samples, ""
        # Each run's first node, and its last where a push made the velocity jump (both sides
        # kept: the interpolation on each side of the jump uses its own) and at the end.
        jumps = [p.time_in_step for p in self._applied]
        ends = [any(abs(run[0][-1] - t) < 1e-12 for t in jumps) for run in runs[:-1]] + [True]
        nodes = tuple(np.concatenate([part for run, end in zip(runs, ends) for part in (run[k][:1], run[k][1:2 * end])])
                      for k in range(4))
        q, qd = hermite_samples(nodes, np.array(taus), side="left")
        evaluated = self.samples.dynamics(q, qd)
        for k, tau in enumerate(taus):
            samples.append(Sample(s.t + tau, tau, q[k], qd[k], evaluated.grf[k], s.step, s.stance_side, s.stance_foot))
            self.sample_index += 1
            fall = self._fall(samples[-1], float(evaluated.lowest_link[k]))
            if fall:
                return samples, fall
        return samples, ""

    def _fall(self, sample: Sample, lowest_link: float) -> str:
        """Why ``sample`` is a fall ('' if it is not); ``lowest_link``: the height (m) of its
        lowest knee, hip, shoulder or hand."""
        if not sample.grf[2] > 0.0:
            return f"vertical ground reaction not positive ({sample.grf[2]:.3g} N) at t = {sample.t:.4f} s"
        if sample.t_step > 0.05 * self.period and lowest_link < 0.0:
            return f"a link went below the ground at t = {sample.t:.4f} s"
        return ""

    def _double_support(self, q_td: np.ndarray, qd_td: np.ndarray, t_step: float) -> Touchdown:
        """Impulses from the actual pre-impact state towards the plan, then the leg exchange."""
        bm, s = self.bm, self.state
        error = max(float(np.max(np.abs(q_td - self.q_t))), float(np.max(np.abs(qd_td - self.qd_b))))
        foot_line_moment = self.orbit.foot_line_moment  # the plan's, of this double support
        ending = (self.q_t, self.qd_b)  # the plan's touchdown, before the aim moves to the next step
        if self._next_cycle is not None:
            offset = self.steering.offset if self.steering is not None else None
            self._cycle = self._prepared(self._next_cycle, offset)
            self._next_cycle = None
            self._aim_at(0 if len(self._cycle) == 1 or other_side(s.stance_side) == "right" else 1)
        elif len(self._cycle) > 1:  # a stride: the next step is the cycle's next
            self._aim_at((self._index + 1) % len(self._cycle))
        impact = self.hybrid.impact(q_td)
        planned = impact.problem(qd_td, self.qd_a)
        reachable, miss = planned.reachable()
        for again in range(CLOSURE_ROUNDS):  # legs leaning: the re-aim's closure matched to what the spin moments do
            if self.reaim:
                try:
                    qd_next = self._reaim(self.hybrid.exchange.configuration(q_td), impact, planned.xd_b,
                                          foot_line_moment, again > 0)
                except Fall as exc:
                    momentum = float(impact.momentum_row @ planned.xd_b)
                    planned_momentum = float(self.hybrid.impact(ending[0]).momentum_row @ bm.embed(ending[1]))
                    raise Fall(f"{exc} (at t = {s.t + t_step:.4f} s the momentum about the feet line, which no "
                               f"impulse changes, is {momentum:.2f} kg m^2/s where the plan's is "
                               f"{planned_momentum:.2f}, the touchdown {error:.3g} from the plan's state)") from None
                problem = replace(planned, xd_a=impact.next_step_velocity(qd_next))
            else:
                problem = reachable
            xd_a = problem.xd_a
            if not np.all(np.isfinite(xd_a)):
                raise Fall(f"no reachable velocity after the touchdown at t = {s.t + t_step:.4f} s")
            sol = solve_impulses(problem, self.orbit.effort, self.orbit.options)
            if not sol.success:
                raise Fall(f"the double support at t = {s.t + t_step:.4f} s has no solution ({sol.message}): "
                           f"{self._why_no_impulses(problem)}")
            done = sol.foot_line_moment(problem)
            if not self.reaim or abs(done - foot_line_moment) <= self.settings.tolerance:
                break
            foot_line_moment = done
        # The new stance foot's world position, then the mirror: the next step in model coordinates.
        tip = bm.swing_tip(q_td)
        new_foot = s.stance_foot + s.axes @ tip
        new_foot[2] = 0.0
        exchange, side = self.hybrid.exchange, other_side(s.stance_side)
        self.state = WalkState(
            q=exchange.configuration(q_td),
            qd=exchange.velocity(q_td, xd_a),
            step=s.step + 1,
            t=s.t + t_step,
            stance_side=side,
            stance_foot=new_foot,
            heading=next_heading(s.heading, side, exchange.heading(q_td)),
        )
        return Touchdown(
            step=s.step, t=s.t + t_step, t_step=t_step, i_minus=sol.i_minus.copy(), i_plus=sol.i_plus.copy(),
            W=sol.W, state_error=error, velocity_miss=abs(miss),
            correction=float(np.max(np.abs(xd_a[3:] - planned.xd_a[3:]))), equation_residual=sol.equation_residual,
            next_stance_side=self.state.stance_side,
        )

    def _why_no_impulses(self, problem) -> str:
        """The physical reason a double support has no impulses: the friction cone (the impulses
        exist without it, needing the friction they need: a finite coefficient, or none at all when
        a foot would need a horizontal impulse with no vertical one), the joint-rate bound, or
        none reaches the aimed velocity with the feet pushing on the ground."""
        options = self.orbit.options
        if math.isfinite(options.friction):
            free = solve_impulses(problem, self.orbit.effort, replace(options, friction=math.inf))
            if free.success:
                needed = float(friction_ratios(free).max())
                if not math.isfinite(needed):
                    return (f"the impulses would need a foot to take a horizontal reaction impulse with no vertical one: "
                            f"no friction coefficient suffices (the ground's is {options.friction:g})")
                return f"the impulses would need a friction coefficient of {needed:.2f}, more than the ground's {options.friction:g}"
        if math.isfinite(options.rate_bound):
            if solve_impulses(problem, self.orbit.effort, replace(options, rate_bound=math.inf)).success:
                return f"the impulses would need joint rates above the bound of {options.rate_bound:g} rad/s"
        return "no impulses reach the aimed velocity with the feet pushing on the ground (unilateral contact)"

    def _reaim(self, q_start: np.ndarray, impact: ImpactMap, xd_b: np.ndarray, foot_line_moment: float,
               again: bool = False) -> np.ndarray:
        """The next step's initial velocity (its own coordinates, rad/s), and its duration
        (``next_period``, s): the flow from ``q_start`` reaches the planned touchdown
        configuration q_T exactly, and the velocity is reachable through this double support
        (the momentum about the feet line is kept, up to the ``foot_line_moment`` (kg m^2/s) the
        ground's spin moments change); ``again``: the same touchdown as the last re-aim, with
        another ``foot_line_moment`` (a closure round).

        Chord steps with the planned orbit's Jacobian: off the orbit by a numerical error
        only, they converge to rounding level in one or two steps. With momentum steering, the
        steered re-aim (``steering``) instead.
        """
        if self.steering is not None:
            try:
                q_pre = self.hybrid.exchange.configuration(q_start)  # the exchange is an involution
                v, self.next_period, _ = self.steering.solve(q_pre, impact, xd_b, self.next_period, foot_line_moment,
                                                             again)
            except SteeringFailed as exc:
                raise Fall(str(exc)) from None
            return v
        gain, _ = impact.closure_gradients()  # d(momentum after)/d(qd_next)
        target_momentum = float(impact.momentum_row @ xd_b) - foot_line_moment
        n = self.bm.nq
        jac = np.zeros((n + 1, n + 1))
        jac[:n, :n], jac[:n, n], jac[n, :n] = self._phi_qv, self.qd_b, gain

        def residual(x: np.ndarray):
            v, duration = x[:n], x[n]
            if not duration > 0:
                return np.full(n + 1, np.nan), None
            with np.errstate(over="ignore", invalid="ignore"):
                run = self.step_flow.propagate(q_start, v, duration)
            return np.append(run.q - self.q_t, gain @ v - target_momentum), None

        x0 = np.append(self.qd_a, self.next_period)
        result = newton.chord(residual, x0, jac, 1e-12, self.settings.reaim_steps)
        if result.status == newton.DIVERGED:
            raise Fall("re-aiming the next step diverged: the state is too far from the plan")
        if not result.converged:
            raise Fall("re-aiming the next step did not converge: the state is too far from the plan")
        self.next_period = float(result.x[n])
        return result.x[:n]


class Walk:
    """A plan in, an iterator of samples and events out.

    Iterating yields, in time order: ``Sample`` (every 1 / ``rate`` s of simulated time, with
    the robot in world terms), ``AppliedPush`` where a push acted, ``Touchdown`` at the end of
    each step, and at the end one of ``Finished`` (``steps`` steps made; 0 means never),
    ``Fell``, or ``CouldNotStart`` (then nothing else). ``batches`` yields the same with the
    samples between two events at once, as arrays. ``model`` and ``world`` (None if it could not
    start) describe the robot. ``momentum_rate``: the walker's momentum steering (``Walker``);
    ``before_step``: called with the walker before each step (pushes to apply, a gait to aim at:
    ``Walker.push``, ``Walker.retarget``); ``engine``: one of ``ENGINES``, with ``pulse_duration``
    (s) the MuJoCo engine's double support (``mujoco_engine``).
    """

    def __init__(self, orbit: PlannedOrbit | Cycle, rate: float, steps: int = 0, reaim: bool = True,
                 settings: Settings = DEFAULTS, momentum_rate: float | None = None,
                 before_step: Callable[[Walker], object] | None = None, engine: str = "hybrid",
                 pulse_duration: float = PULSE_DURATION) -> None:
        if engine not in ENGINES:
            raise ValueError(f"unknown engine {engine!r}: use one of {', '.join(ENGINES)}")
        if not rate > 0:
            raise ValueError(f"publishing rate must be positive, got {rate}")
        if steps < 0:
            raise ValueError(f"steps must be 0 (no end) or positive, got {steps}")
        cycle = as_cycle(orbit)
        self.orbit, self.rate, self.steps = cycle[0], rate, steps
        self.before_step = before_step
        self.problem = ""
        self.model: BipedModel | None = None
        self.world: WorldView | None = None
        self.walker: Walker | None = None
        if not all(o.converged for o in cycle):
            self.problem = "the plan did not converge"
            return
        if not all(o.admissible for o in cycle):
            self.problem = "the plan is not admissible: " + "; ".join(r for o in cycle for r in o.reasons)
            return
        try:
            self.model = BipedModel.from_params(load_params(self.orbit.params or None))
        except ValueError as exc:
            self.problem = str(exc)
            return
        self.world = WorldView(self.model)
        hybrid, stepper = HybridStep(self.model), None
        if engine == "mujoco":
            from .mujoco_engine import MujocoEngine  # MuJoCo is loaded only for its walks
            stepper = MujocoEngine(hybrid, rate, pulse_duration)
        self.walker = Walker(hybrid, cycle, rate, reaim, settings, momentum_rate, stepper)

    def __iter__(self) -> Iterator[Sample | AppliedPush | Touchdown | Fell | Finished | CouldNotStart]:
        for item in self.batches():
            if isinstance(item, StepSamples):
                for k, sample in enumerate(item.samples):
                    yield replace(sample, world=item.world.state(k))
            else:
                yield item

    def batches(self) -> Iterator[StepSamples | AppliedPush | Touchdown | Fell | Finished | CouldNotStart]:
        """As iterating, but the samples of a step come at once, as a ``StepSamples`` (arrays);
        a push within a step splits them: the samples before it, the push, the samples after."""
        if self.walker is None:
            yield CouldNotStart(self.problem)
            return
        walker, world = self.walker, self.world
        while self.steps == 0 or walker.state.step < self.steps:
            if self.before_step is not None:
                self.before_step(walker)
            s = walker.state
            outcome = walker.walk_step()
            pushes = list(outcome.pushes)
            if outcome.samples:
                pictures = world.pictures(np.array([x.q for x in outcome.samples]),
                                          np.array([x.qd for x in outcome.samples]), s.stance_side, s.stance_foot,
                                          s.heading)
                times = np.array([x.t for x in outcome.samples])
                start = 0
                for push in pushes:  # each before the first sample at or after it
                    end = int(np.searchsorted(times, push.t, side="left"))
                    if end > start:
                        yield StepSamples(outcome.samples[start:end], pictures.rows(start, end))
                    yield push
                    start = max(start, end)
                if start < len(times):
                    yield StepSamples(outcome.samples[start:], pictures.rows(start, len(times)))
            else:
                yield from pushes
            if outcome.touchdown is None:
                t = outcome.samples[-1].t if outcome.samples else s.t
                yield Fell(s.step, t, t - s.t, s.stance_side, outcome.fall)
                return
            yield outcome.touchdown
        yield Finished(walker.state.step, walker.state.t, walker.state.stance_side)
