"""The simulator's pushes: the ``~/push`` service (biped_gait_interfaces/Push) and the scripted
pushes of its ``pushes`` parameter, handed to the walker before the step they act in
(docs/model.md section 8.6). No physics here.

The walker integrates a step before its samples are published (at the real-time factor), so a
push asked for while a step is shown acts in the first step not yet integrated, at its phase: a
fraction of the planned period T of the gait walked. A standing robot makes no steps (its step is
0): a push acts phase x T after the end of what has been integrated, and a scripted push of step 0
phase x T after the standing's start. The service answers once the walker has taken the push
(the step and the walk time it acts at), or ``success = false`` if the robot is not walking.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field

import numpy as np

from ..core.walking.push import Push
from ..core.walking.runner import Walker

SCRIPT_FORMAT = "STEP PHASE PX PY PZ, groups separated by ';'"


@dataclass(frozen=True, eq=False)
class ScriptedPush:
    """A push of the ``pushes`` parameter: in ``step`` (index), at ``phase`` (fraction of T),
    ``impulse`` (N s, world axes)."""

    step: int
    phase: float
    impulse: np.ndarray


def check_push(impulse: np.ndarray, phase: float) -> str:
    """Why a push cannot be made ('' if it can): the impulse (N s) finite, 0 <= phase < 1."""
    if not np.all(np.isfinite(impulse)):
        return f"the impulse must be finite, got {impulse.tolist()}"
    if not (math.isfinite(phase) and 0.0 <= phase < 1.0):
        return f"the phase must be in [0, 1) (a fraction of the step's period), got {phase}"
    return ""


def parse_pushes(text: str) -> list[ScriptedPush]:
    """The scripted pushes of ``text`` (``SCRIPT_FORMAT``, e.g. '4 0.5 2.0 0 0; 9 0.3 0 -1.5 0');
    ``ValueError`` with one line if it is malformed."""
    pushes = []
    for group in filter(None, (g.strip() for g in text.split(";"))):
        fields = group.split()
        try:
            numbers = [float(f) for f in fields]
        except ValueError:
            numbers = []
        if len(numbers) != 5 or not numbers[0].is_integer() or numbers[0] < 0:
            raise ValueError(f"parameter pushes: expected {SCRIPT_FORMAT} with a step index >= 0, got {group!r}")
        impulse, phase = np.array(numbers[2:]), numbers[1]
        problem = check_push(impulse, phase)
        if problem:
            raise ValueError(f"parameter pushes: {problem} in {group!r}")
        pushes.append(ScriptedPush(int(numbers[0]), phase, impulse))
    return pushes


@dataclass
class _Request:
    """A service call waiting for the walker: its push and, once taken, the answer."""

    impulse: np.ndarray
    phase: float
    taken: threading.Event = field(default_factory=threading.Event)
    answer: tuple[bool, str, int, float] = (False, "", 0, 0.0)


class PushScheduler:
    """The pushes waiting for the walker: scripted ones and service calls. ``before_step`` runs
    in the walker's thread, ``request`` in the service's."""

    def __init__(self, scripted: list[ScriptedPush]) -> None:
        self.scripted = scripted
        self._lock = threading.Lock()
        self._requests: list[_Request] = []
        self._walking = False
        self._scripted_step: int | None = None  # the step whose scripted pushes were given last

    def start(self) -> None:
        """The walk began: service calls are taken from now on."""
        self._scripted_step = None
        with self._lock:
            self._walking = True

    def stop(self, reason: str) -> None:
        """The walk ended (``reason``): waiting calls and later ones fail."""
        with self._lock:
            self._walking = False
            waiting, self._requests = self._requests, []
        for request in waiting:
            request.answer = (False, f"the robot is not walking: {reason}", 0, 0.0)
            request.taken.set()

    def request(self, impulse: np.ndarray, phase: float, timeout: float) -> tuple[bool, str, int, float]:
        """Hand a push to the walker; (success, message, step, walk time it acts at) once the
        walker took it, or a failure if the robot is not walking or ``timeout`` (s) passes."""
        problem = check_push(impulse, phase)
        if problem:
            return False, problem, 0, 0.0
        request = _Request(np.asarray(impulse, float), phase)
        with self._lock:
            if not self._walking:
                return False, "the robot is not walking", 0, 0.0
            self._requests.append(request)
        if not request.taken.wait(timeout):
            with self._lock:
                if request in self._requests:
                    self._requests.remove(request)
                    return False, f"the walker did not take the push within {timeout:g} s", 0, 0.0
        return request.answer

    def before_step(self, walker: Walker) -> None:
        """Give ``walker`` the pushes of the step it is about to walk (or, standing, of what it is
        about to integrate from ``t_step`` s into its step on)."""
        step, start, period, offset = walker.state.step, walker.state.t, walker.period, walker.state.t_step
        if step != self._scripted_step:
            self._scripted_step = step
            for scripted in self.scripted:
                if scripted.step == step:
                    walker.push(Push(scripted.impulse, scripted.phase * period))
        with self._lock:
            waiting, self._requests = self._requests, []
        for request in waiting:
            walker.push(Push(request.impulse, offset + request.phase * period))
            when = start + offset + request.phase * period
            request.answer = (True, f"push of {np.round(request.impulse, 6).tolist()} N s in step {step} at "
                              f"t = {when:.4f} s", step, when)
            request.taken.set()
