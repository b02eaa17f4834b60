"""The gait-planner node (entry point ``biped-gait-planner``).

- service ``~/plan_gait`` (biped_gait_interfaces/srv/PlanGait): plan one gait; with
  ``double_support`` > 0, its periodic cycle with a double support that lasts, with
  ``actuated_swing`` > 0 the cycle whose swing is actuated at its two ends (each an IPOPT solve of
  seconds to minutes, on a thread of its own: the node serves the rest meanwhile); with
  ``start_stop``, its start from standing and stop to standing (the package's kept ones);
- action ``~/optimize_arm_swing`` (biped_gait_interfaces/action/OptimizeArmSwing): the arm
  amplitude of least effort, with feedback per amplitude evaluated; cancelable;
- topic ``~/gait_plan`` (biped_gait_interfaces/msg/GaitPlan): every successful plan, reliable,
  transient-local, depth 1, so a late subscriber gets the latest one;
- ``/diagnostics`` (diagnostic_msgs/DiagnosticArray, every second): requests, solves and their
  times, cache hits, refusals, optimizations, the recording;
- recording (parameter ``record``): every request with its response (PlanGaitCall messages on
  ``~/plan_gait/calls``), every published plan and ``/diagnostics``, to MCAP under
  ``record_dir``, by a writer thread: an exchange is queued as it is answered and serialized and
  written off the request path.

A thin node: requests and goals carry the gait vocabulary (``biped_gait.gait_options``: the
same fields, units and meanings as the command line's options), converted and handed to the
core (``GaitPlanner``); nothing a client sends can stop it (bad input gets ``success = false``
and a message; text from a request is clipped in the log). Identical requests and goals are
answered from caches (``cache_size`` each). The service's and the action's request queues hold
``queue_depth`` requests, so that a burst is answered, not dropped. ``cache_size`` and
``record`` can be set at run time (parameter services); the others are read at start. A
recording that fails (disk full, folder not writable or deleted) is one error line and the node
keeps serving without recording. The default parameter
set's planners (the service's and the action's, with their atlases) are made at start-up by a
thread of their own, while the node comes up, so that the first request is answered at the speed
of the next ones; a request that comes before they are ready waits for them.
"""

from __future__ import annotations

import copy
import math
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from datetime import datetime, timezone

from . import environment  # noqa: F401  (before rclpy: keep discovery local)

import rclpy.logging  # after a signal, a logger of no node: rosout is gone with the context

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.qos import QoSProfile
from rclpy.task import Future
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory

from biped_gait_interfaces.action import OptimizeArmSwing
from biped_gait_interfaces.msg import GaitPlan, PlanGaitCall
from biped_gait_interfaces.srv import PlanGait

from ..core.model.params import DEFAULT_PARAMS, load_params, names_set, shipped_param_names
from ..core.gait import views
from ..core.gait.planner import SEED, GaitPlanner, GaitRequest, lasting_request, swing_request
from ..core.dynamics.settings import DEFAULTS
from ..core.model.text import clip
from ..recording import topics
from ..recording.background import BackgroundRecorder
from ..recording.writer import McapRecorder, RecordingError
from ..core.gait.arm_optimum import Canceled, NoAdmissibleGait, expected_solves, optimal_arm_amplitude
from .conversions import (OPTION_NAMES, POINT_NAMES, gait_fields, phase_msg, plan_msg, request_key, stride_msgs,
                          swing_phases_msg, urdf_joints)
from .diagnostics import OK, WARN, Counters, Diagnostics, Report
from .diagnostics import QOS as DIAGNOSTICS_QOS, TOPIC as DIAGNOSTICS_TOPIC
from .parameters import Param, declare
from .process import Usage, run_node
from .qos import EVENTS, LATCHED
from .recorded import RecordedPublisher, finish_recording

NODE_NAME = "biped_gait_planner"
PLAN_FRAME = "stance_foot"  # plans are expressed with the stance tip at the origin
GOAL_NAMES = ("step_length", "period", "alpha_min", "alpha_max", "alpha_step")  # a goal's fields beyond the options
CLOSE_WAIT = 1.0  # s that closing waits for a callback in flight (a solve takes tens of ms; a lasting one is not waited for)
GROUPS = ("service", "action")  # who owns a planner: the service's callbacks, the action's
PARAMETERS = (
    Param("default_params", DEFAULT_PARAMS, "parameter set used when a request names none: "
          f"{', '.join(shipped_param_names())} or the path of a YAML file (which requests may name by its path or "
          "by the name inside it)"),
    Param("bvp_tolerance", DEFAULTS.tolerance, "bound on the BVP end-point residual (rad) and closure gap "
          "(kg m^2/s)", 1e-14, 1e-6),
    Param("max_iterations", DEFAULTS.max_iterations, "Newton iterations allowed per solve (count)", 1, 200),
    Param("trajectory_samples", DEFAULTS.samples, "samples of the ballistic step in each plan's trajectory (count)",
          2, 2001),
    Param("cache_size", 256, "answers kept for identical requests, and for identical goals (count)", 0, 100000,
          dynamic=True),
    Param("queue_depth", 1000, "requests each service and the action keep waiting (count): a burst beyond "
          "this is dropped by the middleware", 10, 100000),
    Param("record", True, "record requests, responses, plans and /diagnostics to MCAP (true/false; at run time: "
          "false finishes the recording, true starts a new one)", dynamic=True),
    Param("record_dir", topics.RECORD_DIR, "directory of the recordings (path)"),
)


@dataclass(frozen=True)
class CachedAnswer:
    """A plan_gait answer kept for identical requests: its success and message, the plan, and
    the plan without its trajectory's points (for ``omit_trajectory``)."""

    success: bool
    message: str
    plan: GaitPlan
    compact: GaitPlan
    next_steps: tuple[GaitPlan, ...] = ()
    next_compact: tuple[GaitPlan, ...] = ()


def without_trajectory(plan: GaitPlan) -> GaitPlan:
    """``plan`` with its trajectory's joint names but none of its points."""
    compact = copy.copy(plan)
    compact.trajectory = JointTrajectory(header=plan.trajectory.header, joint_names=plan.trajectory.joint_names)
    return compact


class InFlight:
    """Counts the callbacks running (``with in_flight:``), so that closing can wait for them
    before the node's handles go away."""

    def __init__(self) -> None:
        self._count = 0
        self._idle = threading.Condition()

    def __enter__(self) -> "InFlight":
        with self._idle:
            self._count += 1
        return self

    def __exit__(self, *_exc) -> None:
        with self._idle:
            self._count -= 1
            self._idle.notify_all()

    @contextmanager
    def aside(self) -> Iterator[None]:
        """Not counted inside: a callback awaiting another thread's work uses no handle, and
        closing need not wait for that work (a lasting solve: seconds)."""
        self.__exit__()
        try:
            yield
        finally:
            self.__enter__()

    def wait_idle(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for no callback to run; False if one still does."""
        with self._idle:
            return self._idle.wait_for(lambda: self._count == 0, timeout)


class GaitPlannerNode(Node):
    """Serves gait plans and arm-swing optimizations computed by the core."""

    def __init__(self, **kwargs) -> None:
        super().__init__(NODE_NAME, **kwargs)
        self._cache_lock = threading.Lock()
        self._cache: OrderedDict[tuple, CachedAnswer] = OrderedDict()
        self._goal_cache: OrderedDict[tuple, OptimizeArmSwing.Result] = OrderedDict()
        self.recorder: BackgroundRecorder | None = None
        self._recordings: list[RecordedPublisher] = []
        value = declare(self, PARAMETERS, self._on_parameter)
        self._default_params = value["default_params"]
        self._default_set = load_params(self._default_params)  # refuse to start on a bad default, with its message
        self._planners: dict[tuple[str, str], GaitPlanner] = {}
        self._cache_size = value["cache_size"]
        self._sequence = 0
        self._closing = threading.Event()
        self._in_flight = InFlight()
        self.stats = Counters(("requests", "solves", "cache_hits", "refusals", "optimizations",
                               "optimization_cache_hits"))
        self.settings = replace(DEFAULTS, samples=value["trajectory_samples"], tolerance=value["bvp_tolerance"],
                                max_iterations=value["max_iterations"])
        self._record_dir = value["record_dir"]
        self.plan_publisher = RecordedPublisher(self, GaitPlan, "~/gait_plan", LATCHED, None)
        self.call_recorder = RecordedPublisher(self, PlanGaitCall, "~/plan_gait/calls", EVENTS, None, publish=False)
        health = RecordedPublisher(self, DiagnosticArray, DIAGNOSTICS_TOPIC, DIAGNOSTICS_QOS, None)
        self._recordings = [self.plan_publisher, self.call_recorder, health]
        self._prepared = {group: threading.Event() for group in GROUPS}
        threading.Thread(target=self._prepare, name="prepare_planners", daemon=True).start()
        if value["record"]:
            try:
                self._start_recording()
            except ValueError as exc:
                self.get_logger().error(f"{exc}; serving without recording")
        # One group each: the service keeps answering while an optimization runs; each group
        # owns its planners (Pinocchio data are not shared between threads).
        self._service_group = MutuallyExclusiveCallbackGroup()
        self._action_group = MutuallyExclusiveCallbackGroup()
        # The service's callbacks run in the spinning thread (a cached answer at once; a solve,
        # tens of ms, there too; a lasting double support's seconds on a thread of their own,
        # ``_lasting``), the action's on the executor's pool.
        self.inline_callback_groups = (self._service_group,)
        queue = QoSProfile(depth=value["queue_depth"])  # reliable, volatile, like the services' default
        self.plan_service = self.create_service(
            PlanGait, "~/plan_gait", self._on_plan_gait, qos_profile=queue, callback_group=self._service_group
        )
        self.optimize_server = ActionServer(
            self,
            OptimizeArmSwing,
            "~/optimize_arm_swing",
            execute_callback=self._on_optimize,
            goal_callback=lambda _goal: GoalResponse.ACCEPT,
            cancel_callback=lambda _goal: CancelResponse.ACCEPT,
            callback_group=self._action_group,
            goal_service_qos_profile=queue,
            result_service_qos_profile=queue,
            cancel_service_qos_profile=queue,
        )
        self.diagnostics = Diagnostics(self, {"planning": self._report}, health)

    # Run-time parameters and recording ------------------------------------------------------
    def _on_parameter(self, name: str, value: object) -> None:
        """Apply a new ``cache_size`` or ``record`` (``ValueError``: refused, with the reason)."""
        if name == "cache_size":
            with self._cache_lock:
                self._cache_size = int(value)
                for cache in (self._cache, self._goal_cache):
                    while len(cache) > self._cache_size:
                        cache.popitem(last=False)
        elif name == "record" and value and self.recorder is None:
            self._start_recording()
        elif name == "record" and not value and self.recorder is not None:
            self._stop_recording()

    def _start_recording(self) -> None:
        """Record from now on, to a new file under ``record_dir``; ``ValueError`` if it cannot."""
        stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%S_%f")
        try:
            recorder = BackgroundRecorder(McapRecorder(self._record_dir, f"planner_{stamp}"),
                                          on_failure=lambda error: self.get_logger().error(f"{error}; serving without recording"))
        except RecordingError as exc:
            raise ValueError(str(exc)) from None
        for publisher in self._recordings:
            publisher.record_to(recorder)
        self.recorder = recorder
        self.get_logger().info(f"recording to {recorder.path}")

    def _stop_recording(self) -> None:
        """Finish the recording (what is queued is written)."""
        recorder, self.recorder = self.recorder, None
        finish_recording(self._recordings, recorder, self.get_logger())

    def _report(self) -> Report:
        """The planning part of ``/diagnostics``."""
        figures = self.stats.figures()
        with self._cache_lock:
            figures.update(cached_plans=len(self._cache), cached_optimizations=len(self._goal_cache),
                           cache_size=self._cache_size)
        recorder = self.recorder
        figures["recording"] = recorder.path if recorder is not None else "off"
        if recorder is not None and recorder.failure:
            return Report(WARN, f"serving; recording failed: {clip(recorder.failure)}", figures)
        return Report(OK, f"serving: {figures['requests']} requests, {figures['solves']} solves, "
                      f"{figures['cache_hits']} cache hits, {figures['refusals']} refused", figures)

    def _prepare(self) -> None:
        """Make the default parameter set's planner of each group (the service's first) and plan
        the seed gait with it, the plan's message included (what a process does once: atlases,
        caches, first calls), so that the first request costs what the next ones do; each is
        handed out by ``_planner`` once ready."""
        for group in GROUPS:
            try:
                planner = GaitPlanner(self._default_params, self.settings, on_note=self.get_logger().warning)
                self._planners[(group, self._default_params)] = planner
                plan_msg(planner.plan(GaitRequest(*SEED)), self._header(), urdf_joints(planner.model))
            except Exception as exc:  # noqa: BLE001  a request meets the same failure and answers it
                self.get_logger().warning(f"preparing the {group}'s planner failed: {clip(repr(exc))}")
            finally:
                self._prepared[group].set()

    def _fields(self, msg, names: tuple[str, ...]) -> dict[str, object]:
        """The ``GaitRequest`` fields ``names`` of a request or goal, its ``params`` the default
        set's as given (``default_params``) whenever it names that set: empty, by its name or by
        its file's path (``names_set``), so that one set is one planner and one cache entry."""
        fields = gait_fields(msg, self._default_params, names)
        if names_set(fields["params"], self._default_set, self._default_params):
            fields["params"] = self._default_params
        return fields

    def _planner(self, params: str, group: str) -> GaitPlanner:
        """The planner of ``group`` for parameter set ``params`` (the default set's made at
        start-up, ``_prepare``: waited for; any other on first use)."""
        if params != self._default_params and params not in shipped_param_names():
            raise ValueError(f"unknown parameter set {clip(repr(params))}: give one of {', '.join(shipped_param_names())}")
        self._prepared[group].wait()
        key = (group, params)
        if key not in self._planners:
            self._planners[key] = GaitPlanner(params, self.settings, on_note=self.get_logger().warning)
        return self._planners[key]

    def _header(self) -> Header:
        return Header(stamp=self.get_clock().now().to_msg(), frame_id=PLAN_FRAME)

    async def _on_plan_gait(self, request: PlanGait.Request, response: PlanGait.Response) -> PlanGait.Response:
        if self._closing.is_set():
            response.success, response.message = False, "the planner is stopping"
            return response
        with self._in_flight:
            return await self._serve(request, response)

    async def _serve(self, request: PlanGait.Request, response: PlanGait.Response) -> PlanGait.Response:
        self.stats.count("requests")
        try:
            await self._answer(request, response)
        except ValueError as exc:
            response.success, response.message = False, str(exc)
        except Exception as exc:  # noqa: BLE001  a solver failure must not take the node down
            self.get_logger().error(f"plan_gait failed: {clip(repr(exc))}")
            response.success, response.message = False, f"internal error: {clip(repr(exc))}"
        if not response.success:
            self.stats.count("refusals")
            self.get_logger().warn(f"plan_gait refused: {clip(response.message)}")
        self._record_call(request, response)
        return response

    async def _answer(self, request: PlanGait.Request, response: PlanGait.Response) -> None:
        """Answer from the cache (the first answer's success and message, marked cached), else
        plan: ``success`` only for an admissible gait; otherwise the reasons (a gait that misses
        only the margins says so) and, when the atlas knows, where the nearest admissible gaits are.
        With ``double_support`` > 0, the gait's cycle with that double support too (``_lasting``);
        with ``actuated_swing`` > 0, the cycle whose swing is actuated at its two ends (the one a walk
        tracks, ``swing_request``'s ``walkable``), with that double support; with ``start_stop``, the
        gait's start from standing and stop to standing (``kept.kept_phases``: the package's, or refused
        with the reason)."""
        fields = self._fields(request, (*POINT_NAMES, *OPTION_NAMES))
        key = request_key({**fields, "double_support": request.double_support, "actuated_swing": request.actuated_swing,
                           "start_stop": request.start_stop})
        cached = self._cached(self._cache, key)
        if cached is not None:
            self.stats.count("cache_hits")
            response.success = cached.success
            response.plan = cached.compact if request.omit_trajectory else cached.plan
            response.next_steps = list(cached.next_compact if request.omit_trajectory else cached.next_steps)
            response.message = f"{cached.message} (cached)"
            return
        core_request = GaitRequest(**fields)
        lasting = lasting_request(core_request, request.double_support)
        swing = swing_request(core_request, request.actuated_swing, request.double_support, walkable=True)
        if request.start_stop:
            from ..core.walking.kept import check_phases_request, kept_phases  # CasADi's import only when asked
            from ..core.walking.orbit import PlannedOrbit

            check_phases_request(request.double_support, request.actuated_swing)
        planner = self._planner(core_request.params, "service")
        joints = urdf_joints(planner.model)
        if math.isfinite(core_request.turn_radius):
            gait = planner.plan_stride(core_request)
            plan, next_steps = stride_msgs(gait, self._header(), joints)
        else:
            gait = planner.plan(core_request)
            plan, next_steps = plan_msg(gait, self._header(), joints), []
        solve_time = gait.solve_time_s
        response.success = gait.admissible
        if gait.admissible:
            response.message = f"admissible (found by {gait.found})"
        else:
            reasons = "not admissible: " + "; ".join(gait.reasons)
            response.message = f"{reasons}; {gait.hint}" if gait.hint else reasons
        if (lasting is not None or swing is not None) and gait.usable:
            solve = (self._swing_cycle(planner, gait, swing, plan) if swing is not None
                     else self._lasting_cycle(planner, gait, lasting, plan))
            solved, said, seconds = await solve
            solve_time += seconds
            response.success = response.success and solved
            response.message = f"{response.message}; {said}"
        if request.start_stop and gait.usable:
            first = gait.steps[0] if math.isfinite(core_request.turn_radius) else gait
            phases = kept_phases(planner.model, PlannedOrbit.of(first))
            plan.start_phase, plan.stop_phase = (phase_msg(views.double_support_phase(p, math.nan)) for p in phases)
            response.success = response.success and all(p.success for p in phases)
            response.message += "".join(f"; {kind}: {p.message}" for kind, p in zip(("start", "stop"), phases))
        self.stats.count("solves")
        self.stats.time(solve_time)
        answer = CachedAnswer(response.success, response.message, plan, without_trajectory(plan), tuple(next_steps),
                              tuple(without_trajectory(p) for p in next_steps))
        response.plan = answer.compact if request.omit_trajectory else plan
        response.next_steps = list(answer.next_compact if request.omit_trajectory else answer.next_steps)
        self._keep(self._cache, key, answer)
        if response.success:
            self._record(lambda: self.plan_publisher.publish(plan), self.plan_publisher.topic)

    async def _lasting_cycle(self, planner: GaitPlanner, gait, lasting, plan: GaitPlan) -> tuple[bool, str, float]:
        """``gait``'s cycle with the double support that lasts ``lasting`` asks, into ``plan``: whether
        it was solved, what to say of it, the solves' time (s)."""
        support, limit = await self._lasting(lambda: planner.lasting_cycle(gait, lasting))
        plan.double_support_phase = phase_msg(views.double_support_phase(support, limit.effort_total))
        said = (f"double support of {support.duration:g} s: E = {support.effort_total:.3f} N m s "
                f"(E(0+) = {limit.effort_total:.3f})" if support.success else support.message)
        return support.success, said, limit.solve_time_s + support.solve_time_s

    async def _swing_cycle(self, planner: GaitPlanner, gait, swing, plan: GaitPlan) -> tuple[bool, str, float]:
        """``gait``'s cycle whose swing is actuated at its two ends as ``swing`` asks, into ``plan``
        (its ``swing_phases`` and ``double_support_phase``), as ``_lasting_cycle`` (the time: the
        impulsive cycle it starts from, the programs' building and IPOPT's, or the disk cache's,
        ``GaitPlanner.swing_cycle``)."""
        from ..core.gait.actuated_swing import cycle_view  # CasADi only when asked

        started = time.perf_counter()
        cycle = await self._lasting(lambda: planner.swing_cycle(gait, swing))
        seconds = time.perf_counter() - started
        view = cycle_view(cycle)
        plan.swing_phases, plan.double_support_phase = swing_phases_msg(view), phase_msg(view["double_support_phase"])
        said = (f"swing actuated for {cycle.actuated_swing:g} s at each end, double support of "
                f"{cycle.support.duration:g} s: E = {cycle.effort_l1:.3f} N m s, peak torque "
                f"{cycle.peak_torque.max():.1f} N m" if cycle.success else cycle.message)
        return cycle.success, said, seconds

    async def _lasting(self, solve: Callable[[], object]) -> object:
        """``solve()`` (a lasting double support's or an actuated swing's cycle: seconds to minutes of
        IPOPT) on a thread of its own, awaited:
        the spinning thread serves the rest meanwhile (the action, /diagnostics, parameters, a
        stop), the service's callback group held, so that its planner stays one thread's and the
        next requests wait in the queue."""
        done = Future()

        def run() -> None:
            try:
                done.set_result(solve())
            except Exception as exc:  # noqa: BLE001  raised again where it is awaited
                done.set_exception(exc)
            executor = self.executor
            if executor is not None:
                executor.wake()  # resume the awaiting callback now, not at the next spin's timeout

        threading.Thread(target=run, name="lasting_double_support", daemon=True).start()
        with self._in_flight.aside():
            return await done

    def _cached(self, cache: OrderedDict, key: tuple):
        """The answer ``cache`` keeps for ``key`` (made its most recent), or None."""
        with self._cache_lock:
            answer = cache.get(key)
            if answer is not None:
                cache.move_to_end(key)
        return answer

    def _keep(self, cache: OrderedDict, key: tuple, answer: object) -> None:
        """Keep ``answer`` in ``cache`` (the oldest beyond ``cache_size`` dropped)."""
        with self._cache_lock:
            cache[key] = answer
            while len(cache) > self._cache_size:
                cache.popitem(last=False)

    def _record_call(self, request: PlanGait.Request, response: PlanGait.Response) -> None:
        """Record the exchange as a PlanGaitCall, built and serialized on the recorder's thread
        (off the request path); a recording failure is logged, never raised."""
        if self.recorder is None:
            return
        with self._cache_lock:
            self._sequence += 1
            sequence = self._sequence
        stamp = self.get_clock().now()
        success, message, plan, next_steps = response.success, response.message, response.plan, response.next_steps

        def call() -> PlanGaitCall:
            fields = {name: getattr(request, name) for name in PlanGait.Request.get_fields_and_field_types()}
            return PlanGaitCall(header=Header(stamp=stamp.to_msg(), frame_id=PLAN_FRAME), sequence=sequence,
                                success=success, message=message, plan=plan, next_steps=next_steps, **fields)

        self._record(lambda: self.call_recorder.record_later(call, stamp.nanoseconds), self.call_recorder.topic)

    def _record(self, action: Callable[[], None], topic: str) -> None:
        """Publish or record (``action``); a failure is logged, never raised (a recording failure
        is the recorder's ``on_failure``, logged once: the recorder stops)."""
        try:
            action()
        except Exception as exc:  # noqa: BLE001  the answer matters more than its record
            self.get_logger().error(f"publishing or recording on {topic} failed: {clip(repr(exc))}")

    def _on_optimize(self, goal_handle) -> OptimizeArmSwing.Result:
        with self._in_flight:
            return self._optimize(goal_handle)

    def _optimize(self, goal_handle) -> OptimizeArmSwing.Result:
        """Answer a goal from the cache (the first answer, its message marked cached), else
        optimize with feedback per amplitude solved; an optimum found and a range without any
        admissible gait are kept for identical goals."""
        goal = goal_handle.request
        self.stats.count("optimizations")
        try:
            fields = self._fields(goal, (*GOAL_NAMES, *OPTION_NAMES))
            check_instantaneous(goal.double_support)
        except ValueError as exc:
            return self._refuse_goal(goal_handle, OptimizeArmSwing.Result(message=clip(str(exc))))
        key = request_key(fields)
        cached = self._cached(self._goal_cache, key)
        if cached is not None:
            self.stats.count("optimization_cache_hits")
            result = copy.copy(cached)
            result.message = f"{cached.message} (cached)"
            if result.success:
                goal_handle.succeed()
                return result
            return self._refuse_goal(goal_handle, result)
        result, keep = self._optimize_now(goal_handle, fields)
        if keep:
            self._keep(self._goal_cache, key, result)
        if result.success:
            goal_handle.succeed()
        elif goal_handle.is_cancel_requested:
            goal_handle.canceled()
        else:
            self._refuse_goal(goal_handle, result)
        return result

    def _refuse_goal(self, goal_handle, result: OptimizeArmSwing.Result) -> OptimizeArmSwing.Result:
        goal_handle.abort()
        self.stats.count("refusals")
        self.get_logger().warn(f"optimize_arm_swing refused: {result.message}")
        return result

    def _optimize_now(self, goal_handle, fields: dict[str, object]) -> tuple[OptimizeArmSwing.Result, bool]:
        """The optimization of a goal (``fields``: its gait vocabulary's fields and range) and
        whether its answer may be kept for identical goals."""
        result = OptimizeArmSwing.Result()
        evaluated: list[tuple[float, float]] = []
        low, high, step = fields.pop("alpha_min"), fields.pop("alpha_max"), fields.pop("alpha_step")
        length, period, mode, params = (fields.pop(name) for name in ("step_length", "period", "mode", "params"))

        def on_result(gait) -> None:
            effort = gait.W if gait.usable else math.nan
            evaluated.append((gait.arm_amplitude, effort))
            progress = min(0.99, len(evaluated) / expected)
            if self._closing.is_set():
                raise Canceled()
            goal_handle.publish_feedback(OptimizeArmSwing.Feedback(progress=progress, alpha=gait.arm_amplitude, effort=effort))
            if goal_handle.is_cancel_requested or self._closing.is_set():
                raise Canceled()

        keep = False
        try:
            check_goal(length, period, low, high, step)
            expected = expected_solves((low, high), step)
            planner = self._planner(params, "action")
            found = optimal_arm_amplitude(planner, length, period, mode, (low, high), step, on_result=on_result,
                                          options=fields)
        except Canceled:
            result.message = (f"canceled after {len(evaluated)} gaits" if goal_handle.is_cancel_requested else
                              f"the planner is stopping: aborted after {len(evaluated)} gaits")
        except (ValueError, NoAdmissibleGait) as exc:
            result.message = clip(str(exc) or type(exc).__name__)
            keep = isinstance(exc, NoAdmissibleGait)
        except Exception as exc:  # noqa: BLE001  a solver failure must not take the node down
            self.get_logger().error(f"optimize_arm_swing failed: {clip(repr(exc))}")
            result.message = f"internal error: {clip(repr(exc))}"
        else:
            result.success, result.message, result.interior = True, found.describe(), found.interior
            result.alpha_opt, result.effort_opt, result.theta_opt = found.alpha, found.W, found.gait.theta
            keep = True
        evaluated.sort()
        result.alphas = [a for a, _ in evaluated]
        result.efforts = [w for _, w in evaluated]
        return result, keep

    def close(self) -> None:
        """Stop an optimization in progress, let the callback running end (a solve, at most
        ``CLOSE_WAIT`` s), and finalize the MCAP recording (called at shutdown, SIGINT and SIGTERM
        included); ``RecordingError`` if the file could not be finished."""
        self._closing.set()
        self._in_flight.wait_idle(CLOSE_WAIT)
        recorder = self.recorder
        if recorder is not None:
            recorder.close()
            if not recorder.failure:
                rclpy.logging.get_logger("biped_gait.recorder").info(f"{self.get_name()}: recording finalized: {recorder.path}")


def check_goal(step_length: float, period: float, alpha_min: float, alpha_max: float, alpha_step: float) -> None:
    """``ValueError`` (one line) for a goal whose numbers are not finite, whose arm range is not
    0 <= alpha_min < alpha_max < pi/2 (rad) or whose step is not positive; L, T and the options
    are checked by the core."""
    for name, value in (("step_length", step_length), ("period", period), ("alpha_min", alpha_min),
                        ("alpha_max", alpha_max), ("alpha_step", alpha_step)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be a finite number, got {value}")
    if not 0.0 <= alpha_min < alpha_max < math.pi / 2:
        raise ValueError(f"the arm range must satisfy 0 <= alpha_min < alpha_max < pi/2 rad, got "
                         f"[{alpha_min:g}, {alpha_max:g}] rad")
    if not alpha_step > 0:
        raise ValueError(f"alpha_step must be positive, got {alpha_step:g} rad")


def check_instantaneous(double_support: float) -> None:
    """``ValueError`` (one line) for a goal whose double support is not the paper's instantaneous
    one: the search plans 30 and more gaits, and the cycle of each with a double support that lasts
    is an IPOPT solve of seconds to minutes (docs/ros.md)."""
    if double_support != 0.0:
        raise ValueError(f"double_support {double_support:g} s: the arm swing is optimized with the paper's "
                         "instantaneous double support only (0): with one that lasts, each of the 30 and more "
                         "gaits searched is a solve of seconds to minutes (plan_gait plans one)")


def main(args: list[str] | None = None) -> int:
    """Entry point ``biped-gait-planner``: serve until SIGINT or SIGTERM (exit status 0); a bad
    argument or parameter value exits with status 2 and one line."""
    usage = Usage("The gait planner: the plan_gait service, the optimize_arm_swing action and the "
                  "gait_plan topic.", PARAMETERS)
    return run_node(GaitPlannerNode, "biped-gait-planner", args=args, usage=usage)
