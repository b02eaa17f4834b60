"""Walking a planned gait: a plan in, an iterator of samples and events out (the core of the
simulator node; docs/model.md sections 8 and 11).

``Walk`` chooses the engine and the phases from the simulator's vocabulary (``engine``: the
planner's model with the paper's impulsive double supports, or MuJoCo with the double support as
torque pulses of ``pulse_duration``; ``initial_state``: walking on the gait's orbit, or standing
at rest held by the balance controller, ``phases.standing``), runs the walk with the runner
(``runner.Walker``), calls ``before_step`` before each step (pushes, another gait to aim at; while
standing, which has no steps, before each of its phases), and gives each phase's samples with the
robot in world terms (``world``). An orbit whose swing is actuated at its two ends
(``PlannedOrbit.swing_ends``, docs/model.md section 15.1) is walked from its actuated start.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import replace

import numpy as np

from ..dynamics.closed_chain import ClosedChain
from ..dynamics.hybrid import HybridStep
from ..dynamics.settings import DEFAULTS, Settings
from ..model.biped import BipedModel
from ..model.params import load_params
from .balance import STANCE_LENGTH, balance, standing_pose
from .events import CouldNotStart, Fell, Finished, Sample, StepSamples, Touchdown
from .orbit import Cycle, PlannedOrbit, as_cycle
from .phases.actuated import ActuatedStart
from .phases.pulses import Coast, Pulses
from .phases.standing import Standing
from .push import AppliedPush
from .runner import Walker
from .state import WalkState
from .world import WorldView

ENGINES = ("hybrid", "mujoco")
"""How a walk's phases are integrated: ``hybrid``, the planner's own model (``engines/hybrid.py``),
with the paper's impulsive double supports; ``mujoco``, MuJoCo on the exported stance tree
(``engines/mujoco.py``), with the double support as torque pulses (``phases/pulses.py``)."""
PULSE_DURATION = 5e-3  # s: the double support's duration d with the MuJoCo engine
INITIAL_STATES = ("walking", "standing")
"""How a walk begins: ``walking``, on the gait's orbit at the start of a step; ``standing``, at rest
with both feet down, held by the balance controller (``phases.standing``) until the walk ends or a
start sets it off (``Walker.start``, the kept start of the default gait: docs/model.md section 14.3)."""


def check_initial_state(initial_state: str, engine: str) -> None:
    """``ValueError`` (one line) if a walk cannot begin in ``initial_state`` with ``engine``."""
    if initial_state not in INITIAL_STATES:
        raise ValueError(f"unknown initial state {initial_state!r}: use one of {', '.join(INITIAL_STATES)}")
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}: use one of {', '.join(ENGINES)}")


class Walk:
    """A plan in, an iterator of samples and events out.

    Iterating yields, in time order: ``Sample`` (every 1 / ``rate`` s of simulated time, with
    the robot in world terms), ``AppliedPush`` where a push acted, ``Touchdown`` at the end of
    each step, and at the end one of ``Finished`` (``steps`` steps made; 0 means never),
    ``Fell``, or ``CouldNotStart`` (then nothing else). ``batches`` yields the same with the
    samples between two events at once, as arrays. ``model`` and ``world`` (None if it could not
    start) describe the robot. ``momentum_rate``: the walk's momentum steering (``Walker``);
    ``before_step``: called with the walker before each step (pushes to apply, a gait to aim at:
    ``Walker.push``, ``Walker.retarget``); ``engine``: one of ``ENGINES``, with ``pulse_duration``
    (s) the MuJoCo walk's double support (``phases.pulses``); ``initial_state``: one of
    ``INITIAL_STATES`` (``standing``: the walk stands for ``stand_duration`` s of simulated time,
    to the end of the standing phase that reaches it, 0 meaning never; ``steps`` is not used, a
    standing robot making none). A walk that ``before_step`` stops (``Walker.stop``) stands from the
    stop's end for ``stand_duration`` s, or for ever; ``before_step`` is called before each standing
    phase as before each step, and a walk that it starts (``Walker.start``) walks on from the start's
    lift-off. ``stance_length`` (m): the standing posture's, the front foot ahead of the back one (a
    start begins from the posture at its gait's step length).
    """

    def __init__(self, orbit: PlannedOrbit | Cycle, rate: float, steps: int = 0, reaim: bool = True,
                 settings: Settings = DEFAULTS, momentum_rate: float | None = None,
                 before_step: Callable[[Walker], object] | None = None, engine: str = "hybrid",
                 pulse_duration: float = PULSE_DURATION, initial_state: str = INITIAL_STATES[0],
                 stand_duration: float = 0.0, stance_length: float = STANCE_LENGTH) -> None:
        check_initial_state(initial_state, engine)
        if not rate > 0:
            raise ValueError(f"publishing rate must be positive, got {rate}")
        if steps < 0:
            raise ValueError(f"steps must be 0 (no end) or positive, got {steps}")
        if not stand_duration >= 0:
            raise ValueError(f"the standing's duration must be 0 (no end) or positive, got {stand_duration}")
        cycle = as_cycle(orbit)
        first = Coast(Pulses(pulse_duration)) if engine == "mujoco" else None
        self.orbit, self.rate, self.steps = cycle[0], rate, steps
        self.standing, self.stand_duration = initial_state == "standing", stand_duration
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
        if any(o.double_support is not None for o in cycle):
            if engine == "mujoco":
                self.problem = ("a double support that lasts is walked by the hybrid engine only: MuJoCo's floor holds "
                                "each foot sideways, which the plan's closed chain leaves free, and the new foot slides "
                                "(docs/model.md section 14.1)")
                return
            if momentum_rate is not None:
                self.problem = ("a double support that lasts is walked with the duration re-aim (recovery 'duration'): "
                                "the momentum steering moves the touchdown posture off the phase's plan")
                return
        try:
            self.model = BipedModel.from_params(load_params(self.orbit.params or None))
        except ValueError as exc:
            self.problem = str(exc)
            return
        self.world = WorldView(self.model)
        hybrid, stepper = HybridStep(self.model), None
        if engine == "mujoco":
            from .engines.mujoco import MujocoEngine  # MuJoCo is loaded only for its walks
            stepper = MujocoEngine(hybrid, rate)
        if self.standing:
            chain = ClosedChain(self.model, hybrid.exchange)
            try:
                first = Standing(balance(chain, standing_pose(chain, stance_length)))
            except ValueError as exc:  # BalanceError: the posture cannot be held
                self.problem = str(exc)
                return
        if self.orbit.swing_ends is not None and first is None:  # the swing actuated at its ends: from its start
            first = ActuatedStart(self.orbit.swing_ends.start, 0.0)
        self.walker = Walker(hybrid, cycle, rate, reaim, settings, momentum_rate, stepper, first)

    def __iter__(self) -> Iterator[Sample | AppliedPush | Touchdown | Fell | Finished | CouldNotStart]:
        for item in self.batches():
            if isinstance(item, StepSamples):
                for k, sample in enumerate(item.samples):
                    yield replace(sample, world=item.world.state(k))
            else:
                yield item

    def batches(self) -> Iterator[StepSamples | AppliedPush | Touchdown | Fell | Finished | CouldNotStart]:
        """As iterating, but the samples of each phase come at once, as a ``StepSamples`` (arrays); a
        push within a phase splits them: the samples before it, the push, the samples after."""
        if self.walker is None:
            yield CouldNotStart(self.problem)
            return
        walker, prepared, last = self.walker, None, 0.0
        while not self._done(walker):
            if self.before_step is not None and (isinstance(walker.phase, Standing) or walker.state.step != prepared):
                prepared = walker.state.step
                self.before_step(walker)
            s = walker.state
            run = walker.run_phase()
            yield from self._split(run.samples, run.pushes, s)
            last = run.samples[-1].t if run.samples else max(last, s.t)
            if run.fall:
                yield Fell(s.step, last, last - s.t, s.stance_side, run.fall)
                return
            yield from run.events
        yield Finished(walker.state.step, walker.state.t + walker.state.t_step, walker.state.stance_side)

    def _done(self, walker: Walker) -> bool:
        """Whether the walk has made its steps, or stood its duration (from its start, or from the
        end of its stop)."""
        if isinstance(walker.phase, Standing):
            return 0 < self.stand_duration <= walker.state.t_step + 1e-9
        return 0 < self.steps <= walker.state.step

    def _split(self, samples: list[Sample], pushes: tuple[AppliedPush, ...],
               s: WalkState) -> Iterator[StepSamples | AppliedPush]:
        """The samples of a phase that began in ``s``, with the robot in world terms, cut before the
        first sample at or after each push, which comes there."""
        if not samples:
            yield from pushes
            return
        pictures = self.world.pictures(np.array([x.q for x in samples]), np.array([x.qd for x in samples]),
                                       s.stance_side, s.stance_foot, s.heading, np.array([x.torque for x in samples]))
        times = np.array([x.t for x in samples])
        start = 0
        for push in pushes:
            end = int(np.searchsorted(times, push.t, side="left"))
            if end > start:
                yield StepSamples(samples[start:end], pictures.rows(start, end))
            yield push
            start = max(start, end)
        if start < len(times):
            yield StepSamples(samples[start:], pictures.rows(start, len(times)))
