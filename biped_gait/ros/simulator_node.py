"""The simulator node (entry point ``biped-gait-simulator``): fetches a plan, walks it with the
core's ``Walk``, paces it against the wall clock, and publishes and records what it yields.

Plan: the latest on the planner's ``gait_plan`` topic (``plan_source: topic``) or its own
request to the planner's ``plan_gait`` service (``plan_source: service``), whose fields are the
node's parameters of the gait vocabulary (``biped_gait.gait_options``: ``step_length``,
``period``, ``arm_amplitude``, ``mode``, ``params``, ``closure``, ``effort``,
``effort_coordinates``, ``friction``, ``rate_bound``, ``min_clearance``, ``friction_margin``:
the names, units and meanings of the service's fields; checked at start); with
``optimize_arms`` the planner's ``optimize_arm_swing`` action finds the amplitude first. With
``double_support`` > 0 the plan's double support that lasts is tracked, and with
``actuated_swing`` > 0 too its swing actuated at its two ends (the hybrid engine only:
``check_held_phases``, ``held_orbit``; docs/model.md sections 14.1 and 15.1).

Topics (stamps are the walk's simulated time, started at the node's clock: the wall clock, or
with ``use_sim_time`` the simulated time, from 0): ``/clock`` (rosgraph_msgs/Clock, that time,
before each sample; ``sim_clock``), ``/joint_states`` (sensor_msgs/JointState, URDF joint
names, the torques that act: zero in the ballistic single support, the balance controller's while
standing), ``/odom`` (nav_msgs/Odometry, pelvis ``base_link`` in ``world``), ``/angular_momentum``
(biped_gait_interfaces/AngularMomentum), ``/gait_events`` (biped_gait_interfaces/GaitEvent),
``/tf`` (the URDF's moving joints and the pelvis in ``world``), and transient-local
``/gait_phase`` (biped_gait_interfaces/GaitPhase: which foot stands, the step, the double
supports, or standing; a late subscriber learns the current one), ``/robot_description``
(std_msgs/String) and ``/tf_static``. The recording (MCAP, rosbag2
directory under ``record_dir``, handed over by a thread to a recorder process of its own) holds
the same bytes as were published, of every topic but ``/clock`` (``sim_clock``), and so does
the optional Foxglove live view (``live_view``). Each step's samples come from the walk as
arrays and their messages are serialized at once (``walk_messages``). Controls: ``~/pause``,
``~/resume``, ``~/reset`` and the step counter ``~/iterations`` (``sim_controls``). Every stamp
and log time is on one clock, the simulated time (``SimClock.now_ns``).

Standing, starting and stopping: with ``initial_state`` ``standing`` (the default; ``walking``
begins on the gait's orbit, in mid-stride, at the start of a step) the robot stands at rest,
both feet down, held by the core's balance controller (``core/walking/phases/standing.py``; in
MuJoCo by its own contacts with friction), for ``stand_duration`` s (0: until stopped), publishing and recording as a
walk does (``/gait_phase`` ``STANDING``, ``/odom`` at rest); pushes act on it with both feet held.
A ``/cmd_vel`` that is not 0 starts it onto the plan's gait where the package keeps a start of that
gait (the hybrid engine, the default parameter set's default gait: the robot stands in the start's
posture, and ``/gait_phase`` says ``STARTING`` for its 2 s with both feet down, docs/model.md
section 14.3); elsewhere the core refuses it with the physical reason (``start_stop``, section
8.10), logged once: the robot stands on.
``/cmd_vel`` linear.x 0 asks a walk to stop: the hybrid engine's walk of the gait the package keeps
a stop of (the default parameter set's default gait) stops at the next touchdown on that gait
(``/gait_phase`` ``STOPPING``, 2 s with both feet down) and stands (``STANDING``, for
``stand_duration`` s from then, 0: until stopped; docs/model.md section 14.2); other walks are
refused with the reason and walk on at the slowest gait. No ``/cmd_vel`` for ``cmd_vel_timeout``
s of simulated time counts as a command of 0 (``speed_command``).

Pushes: the ``~/push`` service and the ``pushes`` parameter (``push_service``); the walker
recovers by its per-step re-aim, with momentum steering (``recovery``). Engine: ``engine``
``hybrid`` (the planner's model) or ``mujoco`` (MuJoCo, the double support as torque pulses of
``pulse_duration``; ``core/walking/engines/mujoco.py``, ``core/walking/phases/pulses.py``): the same
topics, events and recording.
Speed and turn: ``/cmd_vel`` (geometry_msgs/Twist in base_link: linear.x in m/s, angular.z in
rad/s), walked with transition steps within the envelope published on ``~/velocity_envelope``
(biped_gait_interfaces/VelocityEnvelope, transient local; ``speed_command``). A live view's
clients (Foxglove's Teleop panel) publish it too: the node puts their ``/cmd_vel`` on the graph
(``teleop``), where its own subscription takes it as any other.

``/diagnostics`` (diagnostic_msgs/DiagnosticArray, every second): the walk's state, steps,
falls, pushes and the recording. ``record`` and ``live_view`` can be set at run time (parameter
services: the recording finished or a new one started, the live view stopped or started); the
other parameters are read at start, and one the node does not have refuses the start.

Outcomes: the walk finished (exit status 0), the robot fell, the walk could not start (a plan
that cannot be walked, a plan naming a parameter set that is neither shipped nor this node's
own ``params`` file, a recording that cannot be made), no plan came (the planner did not
answer, or refused), or the recording failed during the walk (disk full, folder deleted: the
walk ends there, never as a fall): each its own log line (and event, but for the last), and
exit status 1. Waits (for the planner, a plan on the topic, subscribers) are logged every
``LOG_PERIOD`` s and end after ``wait_timeout`` s. With ``exit_when_done`` the process ends
when the walk does; SIGINT and SIGTERM stop it at any time with the recording finished.
"""

from __future__ import annotations

import math
import threading
import time
from contextlib import ExitStack
from dataclasses import replace
from datetime import datetime, timezone

from . import environment  # noqa: F401  (before rclpy: keep discovery local)

import rclpy.logging  # after a signal, a logger of no node: rosout is gone with the context

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
import numpy as np
from rclpy.action import ActionClient
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from sensor_msgs.msg import JointState
from nav_msgs.msg import Odometry
from std_msgs.msg import String, UInt64
from tf2_msgs.msg import TFMessage

from biped_gait_interfaces.action import OptimizeArmSwing
from biped_gait_interfaces.msg import AngularMomentum, GaitEvent, GaitPhase, GaitPlan
from biped_gait_interfaces.srv import PlanGait, Push

from ..core.gait.configurations import GaitMode
from ..core.gait.planner import GaitRequest, validate_request
from ..gait_options import OPTIONS, POINT, GaitOption, resolve_unset
from ..core.walking.pacing import Pacer
from ..core.dynamics.hybrid import HybridStep
from ..core.model.biped import BipedModel
from ..core.model.params import load_params, names_set, shipped_param_names
from ..core.walking.push import AppliedPush
from ..core.dynamics.settings import DEFAULTS
from ..core.walking.steering import DEFAULT_RATE
from ..core.model.text import clip
from ..core.walking.transitions import MAX_CHANGE, MAX_CURVATURE, MAX_CURVATURE_CHANGE, SPEED_RULES
from ..core.walking.events import CouldNotStart, Fell, Finished, StepSamples, Touchdown
from ..core.walking.held_support import lasting_orbit
from ..core.walking.orbit import PlannedOrbit
from ..core.walking.runner import prepare_walking
from ..core.walking.swing_ends import actuated_orbit
from ..core.walking.balance import STANCE_LENGTH
from ..core.walking.kept import kept_gait
from ..core.walking.walk import ENGINES, INITIAL_STATES, PULSE_DURATION, Walk, check_initial_state
from ..recording import topics
from ..recording.background import BackgroundRecorder
from ..recording.recorder_process import RecorderProcess
from ..recording.writer import DEFAULT_CHUNK_SIZE, RecordingError, SampleRows
from .conversions import MODE_TO_MSG, lasting_support_from_msg, orbit_from_msg, swing_cycle_from_msg
from .diagnostics import ERROR, OK, WARN, Counters, Diagnostics, Report
from .diagnostics import QOS as DIAGNOSTICS_QOS, TOPIC as DIAGNOSTICS_TOPIC
from .gait_phase import GaitPhases
from .live_view import DEFAULT_PORT, LiveView
from .parameters import Param, declare
from .process import Usage, run_node
from .qos import EVENTS, LATCHED, STREAM
from .push_service import SCRIPT_FORMAT, PushScheduler, parse_pushes
from .recorded import RecordedPublisher, finish_recording, raw_sender
from .sim_clock import SimClock
from .sim_controls import SimControls
from .speed_command import SpeedCommand
from .teleop import Teleop
from .walk_messages import SampleMessages, event_msg, stamp_msg, tf_msg

NODE_NAME = "biped_gait_simulator"
LOG_PERIOD = 5.0  # s between the log lines of a long wait
CMD_VEL_DEPTH = 10  # /cmd_vel's queue depth: the node's subscription, and its publisher of a live view's clients'
LASTING_PATIENCE = 600.0  # s: the longest wait for a plan with a double support that lasts (the study's slowest: 138 s)
RECORD_EVERY = 16  # samples published between two hand-overs to the recorder (a kill loses them at most)


def _gait_parameter(option: GaitOption) -> Param:
    """The simulator's parameter of one option of the gait vocabulary: the field of its request."""
    if option.name == "params":
        return Param("params", "", "parameter set of the requested plan (a shipped name or a YAML file path); empty: "
                     "the planner's. A plan from the wire is walked only with a shipped set or this file")
    unit = " (rad here; the biped-gait command takes degrees)" if option.degrees else (
        f" ({option.unit})" if option.unit else "")
    return Param(option.name, option.default, f"{option.help}{unit}; for the requested plan", choices=option.choices,
                 finite=False)


GAIT_PARAMETERS = tuple(_gait_parameter(option) for option in (*POINT, *OPTIONS))
GAIT_NAMES = tuple(param.name for param in GAIT_PARAMETERS)
PARAMETERS = (
    Param("plan_source", "service", "where the plan comes from: 'service' requests one, 'topic' walks the latest "
          "one published", choices=("service", "topic")),
    Param("plan_service", "/biped_gait_planner/plan_gait", "the planner's PlanGait service (name)"),
    Param("plan_topic", "/biped_gait_planner/gait_plan", "the planner's GaitPlan topic (name)"),
    Param("optimize_action", "/biped_gait_planner/optimize_arm_swing", "the planner's OptimizeArmSwing action (name)"),
    *GAIT_PARAMETERS,
    Param("optimize_arms", False, "ask the planner's action for the optimal arm amplitude (on its default range) "
          "and walk that, instead of arm_amplitude (true/false)"),
    Param("steps", 0, "steps to walk (count; a walk that began standing counts from its start); 0: until stopped",
          0, 1000000),
    Param("real_time_factor", 1.0, "simulated seconds per wall second; 0: as fast as possible", 0.0, 1000.0),
    Param("publish_rate", 500.0, "samples per second of simulated time (Hz)", 1.0, 100000.0),
    Param("engine", ENGINES[0], "what integrates the walk: 'hybrid' (the planner's model, impulsive double "
          "supports) or 'mujoco' (MuJoCo on the exported stance tree, the double support as torque pulses of "
          "pulse_duration; the walker's re-aim the feedback)", choices=ENGINES),
    Param("double_support", 0.0, "the double support's duration d (s): 0 the paper's instantaneous one; > 0 one that "
          "lasts, both feet down for d s between the paper's two impulses, planned by the planner (an IPOPT solve: "
          "tens of seconds before the walk starts) and tracked by the walk (docs/model.md section 14.1). With "
          "engine 'hybrid' and the duration re-aim (recovery is taken as 'duration'); /cmd_vel is not followed "
          "(a speed change from it does not converge yet)", 0.0, 1.0),
    Param("actuated_swing", 0.0, "the swing actuated for its first and its last tau s (s), with torques within the "
          "joints' effort limits, and ballistic between: 0 the paper's ballistic swing with its impulses; > 0 the cycle "
          "planned by the planner (an IPOPT solve: about a minute before the walk starts) and tracked by the walk "
          "(docs/model.md section 15.1). With double_support > 0, engine 'hybrid' and the 9-joint sets (aoustin2013-hips: "
          "planned, not walked); /cmd_vel is not followed",
          0.0, 1.0),
    Param("pulse_duration", PULSE_DURATION, "with engine 'mujoco': the double support's duration d (s), its "
          "impulses spread into torques over d / 2 before and after the touchdown", 1e-4, 0.1),
    Param("reaim", True, "re-solve each step from the actual state, the open-loop gait being unstable (true/false)"),
    Param("recovery", "momentum", "the re-aim's unknowns: 'duration' (the next step's duration) or 'momentum' "
          "(also the next touchdown's trunk pitch, steering the momentum about the feet line back to the plan's)",
          choices=("momentum", "duration")),
    Param("momentum_rate", DEFAULT_RATE, "with recovery 'momentum': the momentum error's contraction per step "
          "(0: dead-beat)", 0.0, 0.99),
    Param("initial_state", "standing", "how the walk begins: 'standing' (at rest, both feet down, held by the "
          "balance controller for stand_duration, in either engine) or 'walking' (on the gait's orbit, in "
          "mid-stride at the start of a step). /cmd_vel starts a standing robot where a start is kept for its gait "
          "(the hybrid engine, the default gait: docs/model.md section 14.3), else is refused with the physical "
          "reason (section 8.10)", choices=INITIAL_STATES),
    Param("stand_duration", 0.0, "with initial_state 'standing', or after a walk's stop (/cmd_vel 0): how long the "
          "robot stands (s of simulated time, to the next 0.1 s); 0: until stopped. steps counts the steps of a walk",
          0.0, 1e6),
    Param("pushes", "", f"scripted pushes on the trunk: {SCRIPT_FORMAT} (step index, phase as a fraction of T in "
          "[0, 1), impulse in N s, world axes); also the ~/push service"),
    Param("speed_rule", SPEED_RULES[0], "how /cmd_vel speeds pick gaits: 'least_effort' (least W per metre among "
          "walkable atlas gaits; without a current atlas a fixed cadence) or 'cadence' (the plan's period)",
          choices=SPEED_RULES),
    Param("max_speed_change", MAX_CHANGE, "largest change of the walked gait's speed per step (m/s)", 0.001, 1.0),
    Param("max_curvature", MAX_CURVATURE, "largest curvature /cmd_vel turns on, |angular.z / linear.x| (1/m; the "
          "turn radius at least its inverse; models with hip roll and yaw joints)", 0.0, 2.0),
    Param("max_curvature_change", MAX_CURVATURE_CHANGE, "largest change of the walked gait's curvature per step (1/m)",
          0.001, 2.0),
    Param("cmd_vel_timeout", 0.5, "once a /cmd_vel came, no /cmd_vel for this long counts as a command of 0 (s of "
          "simulated time, taken before the next step; 0: never, a real value here, as in diff_drive_controller). "
          "0 m/s asks for a stop (the robot stands, where a stop is kept; else it walks on at the slowest gait)", 0.0, 3600.0),
    Param("record", True, "record everything published but /clock to MCAP (true/false; at run time: false "
          "finishes the recording, true starts a new one, the latched topics first)", dynamic=True),
    Param("record_dir", topics.RECORD_DIR, "directory of the recordings (path)"),
    Param("chunk_size", DEFAULT_CHUNK_SIZE, "MCAP chunk size (bytes): at most this much is lost if the process is "
          "killed", 1024, 64 * 1024 * 1024),
    Param("exit_when_done", False, "end the process when the walk ends (true/false; the launcher sets it)"),
    Param("wait_for_subscribers", 0, "start walking once /joint_states has this many subscribers (count; "
          "discovery can take seconds)", 0, 100),
    Param("live_view", False, "serve a Foxglove WebSocket live view of the walk, whose clients may publish /cmd_vel "
          "(Foxglove's Teleop panel) (true/false; at run time: started or stopped)", dynamic=True),
    Param("live_view_host", "127.0.0.1", "address the live view's server binds (host; 0.0.0.0: every interface)"),
    Param("live_view_port", DEFAULT_PORT, "port of the live view's server (TCP port; 0: any free one)", 0, 65535),
    Param("wait_timeout", 60.0, "how long to wait for the planner's service or action, a plan on the topic, or "
          "the subscribers (s); 0: no limit", 0.0, 86400.0),
)


def check_held_phases(double_support: float, actuated_swing: float, engine: str, params) -> None:
    """``ValueError`` (one line, the physical reason) for phases with the feet held that the walk
    cannot track: in MuJoCo (its floor holds the feet sideways, which the plans' chain leaves free),
    an actuated swing without a double support that lasts (planned at d = 0, not walked), or one of
    the parameter set ``params`` with lateral hip joints (planned, not walked)."""
    for name, value in (("actuated_swing", actuated_swing), ("double_support", double_support)):
        if value > 0.0 and engine != "hybrid":
            raise ValueError(f"{name} {value:g} s needs engine 'hybrid': MuJoCo's floor holds the feet sideways, which "
                             "the plan's closed chain leaves free (docs/model.md section 14.1)")
    if actuated_swing > 0.0 and double_support == 0.0:
        raise ValueError(f"actuated_swing {actuated_swing:g} s needs double_support > 0: the walk lands its actuated "
                         "swing into a double support that lasts (d = 0 is planned, not walked; docs/model.md 15.1)")
    if actuated_swing > 0.0 and params.joints.lateral_hips:
        raise ValueError(f"actuated_swing {actuated_swing:g} s with {params.name}: planned, not walked (its walk's errors "
                         "grow from step to step and it falls in the seventh; docs/model.md 15.1)")


class NoPlan(RuntimeError):
    """No plan to walk: the planner did not answer in time, refused, or the node stopped."""


class SimulatorNode(Node):
    """Walks plans and publishes joint states, pose, angular momentum, transforms and events."""

    def __init__(self, **kwargs) -> None:
        super().__init__(NODE_NAME, **kwargs)
        self._outputs: list[RecordedPublisher] = []
        self._outputs_lock = threading.Lock()  # run-time changes of the recording and the live view
        self.recorder: BackgroundRecorder | None = None
        self.live: LiveView | None = None
        self.teleop: Teleop | None = None  # a live view's clients' /cmd_vel on the graph, from the first live view on
        self.walk_state = "starting"
        self.stats = Counters(("touchdowns", "falls", "pushes"))
        self.value = value = declare(self, PARAMETERS, self._on_parameter)
        check_initial_state(value["initial_state"], value["engine"])
        params = load_params(value["params"] or None)
        check_held_phases(value["double_support"], value["actuated_swing"], value["engine"], params)
        prepare_walking()  # what the walk loads once, now rather than when it starts
        gait = {name: value[name] for name in GAIT_NAMES}
        try:
            validate_request(GaitRequest(**resolve_unset({**gait, "params": ""})), params)
        except ValueError as exc:
            raise ValueError(f"{exc} (the requested plan's parameters: SI units, angles in rad here; the biped-gait "
                             "command takes degrees)") from None
        self.pushes = PushScheduler(parse_pushes(value["pushes"]))
        self.source = value["plan_source"]
        self.rate = value["publish_rate"]
        self.rtf = value["real_time_factor"]
        self.steps = value["steps"]
        self._standing = value["initial_state"] == "standing"
        self._own_params = value["params"]
        self._own_set = params if self._own_params else None
        self._group = ReentrantCallbackGroup()
        self._latest_plan: GaitPlan | None = None
        self._plan_ready = threading.Event()
        self._stop = threading.Event()
        self.exit_requested = threading.Event()
        self.failed = False
        self._recording_failure = ""
        if value["record"]:
            try:
                self.recorder = self._new_recorder()
            except ValueError as exc:
                self._recording_failure = str(exc)
        if value["live_view"]:
            try:
                self.live = self._start_live_view()
            except ValueError as exc:  # the walk goes on without it
                self.get_logger().error(str(exc))

        def publisher(msg_type: type, topic: str, qos) -> RecordedPublisher:
            self._outputs.append(RecordedPublisher(self, msg_type, topic, qos, self.recorder, live=self.live))
            return self._outputs[-1]

        self.pub_joints = publisher(JointState, topics.JOINT_STATES, STREAM)
        self.pub_odom = publisher(Odometry, topics.ODOM, STREAM)
        self.pub_momentum = publisher(AngularMomentum, topics.ANGULAR_MOMENTUM, STREAM)
        self.pub_tf = publisher(TFMessage, topics.TF, STREAM)
        self.pub_events = publisher(GaitEvent, topics.GAIT_EVENTS, EVENTS)
        self.pub_description = publisher(String, topics.ROBOT_DESCRIPTION, LATCHED)
        self.pub_tf_static = publisher(TFMessage, topics.TF_STATIC, LATCHED)
        self.phases = GaitPhases(publisher(GaitPhase, topics.GAIT_PHASE, LATCHED))  # a late subscriber learns it
        self.clock = SimClock(self)
        self.speed = SpeedCommand(self, value["speed_rule"], value["max_speed_change"], value["max_curvature"],
                                  value["max_curvature_change"], publisher, value["cmd_vel_timeout"],
                                  self.clock.now_ns, self.rtf)
        self.create_subscription(Twist, topics.CMD_VEL, self.speed.on_twist, CMD_VEL_DEPTH)
        self.create_service(Push, "~/push", self._on_push, callback_group=self._group)
        self.sampled = {topics.JOINT_STATES: self.pub_joints, topics.ODOM: self.pub_odom,
                        topics.ANGULAR_MOMENTUM: self.pub_momentum, topics.TF: self.pub_tf}
        self.controls = SimControls(self, self._group, publisher(UInt64, topics.ITERATIONS, LATCHED), self.clock.now_ns)
        self._messages: SampleMessages | None = None  # the sampled topics' templates, made with the first walk
        self._actuated: tuple[str, ...] = ()  # the walked model's actuated joints: the events' impulses
        if self.source == "topic":
            self.create_subscription(GaitPlan, value["plan_topic"], self._on_plan, LATCHED, callback_group=self._group)
        self.plan_client = self.create_client(PlanGait, value["plan_service"], callback_group=self._group)
        self.optimize_client = ActionClient(self, OptimizeArmSwing, value["optimize_action"], callback_group=self._group)
        self.diagnostics = Diagnostics(self, {"walk": self._report}, publisher(DiagnosticArray, DIAGNOSTICS_TOPIC,
                                                                               DIAGNOSTICS_QOS), self._group,
                                       self.clock.now_ns)
        self._worker = threading.Thread(target=self._run, name="walker", daemon=True)
        self._worker.start()

    # Outputs changed at run time -------------------------------------------------------------
    def _new_recorder(self) -> BackgroundRecorder:
        """A recording of its own under ``record_dir``; ``ValueError`` if it cannot be made."""
        stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%S_%f")
        try:
            recorder = BackgroundRecorder(RecorderProcess(self.value["record_dir"], f"walk_{stamp}",
                                                          chunk_size=self.value["chunk_size"]),
                                          on_failure=lambda _error: None)  # the walk reads its failure at its next record
        except RecordingError as exc:
            raise ValueError(str(exc)) from None
        self.get_logger().info(f"recording to {recorder.bag_dir}")
        return recorder

    def _start_live_view(self) -> LiveView:
        """The Foxglove live view on ``live_view_host``:``live_view_port``, its clients' /cmd_vel
        published on the graph (``teleop``); ``ValueError`` (one line) if its server cannot start
        (the port taken)."""
        host, port = self.value["live_view_host"], self.value["live_view_port"]
        if self.teleop is None:
            self.teleop = Teleop(self, CMD_VEL_DEPTH)
        try:
            live = LiveView(host, port, on_message=self.teleop.on_message)
        except Exception as exc:  # noqa: BLE001  the SDK's error for a port taken, an address not here
            raise ValueError(f"live view not started on {host}:{port}: {clip(str(exc))}") from None
        self.get_logger().info(f"live view: open Foxglove on ws://{host}:{live.port}")
        return live

    def _on_parameter(self, name: str, value: object) -> None:
        """Start or stop the recording (``record``) or the live view (``live_view``) at run time;
        ``ValueError`` refuses the change with its reason. A step in progress records and shows
        its remaining samples with what it started with (dropped once that is closed)."""
        with self._outputs_lock:
            if name == "record" and value and self.recorder is None:
                self.recorder = self._new_recorder()
                for publisher in self._outputs:
                    publisher.record_to(self.recorder)
            elif name == "record" and not value and self.recorder is not None:
                recorder, self.recorder = self.recorder, None
                finish_recording(self._outputs, recorder, self.get_logger())
            elif name == "live_view" and value and self.live is None:
                self.live = self._start_live_view()
                for publisher in self._outputs:
                    publisher.show_on(self.live)
            elif name == "live_view" and not value and self.live is not None:
                live, self.live = self.live, None
                for publisher in self._outputs:
                    publisher.show_on(None)
                live.close()
                self.get_logger().info("live view stopped")

    def _report(self) -> Report:
        """The walk part of ``/diagnostics``."""
        moving = self.walk_state in ("walking", "standing")
        figures = {"state": "paused" if self.controls.paused and moving else self.walk_state,
                   "samples": self.controls.iterations, **self.stats.figures()}
        commanded = self.speed.commanded
        figures["commanded speed (m/s)"] = f"{commanded:.4f}" if commanded is not None else "none"
        recorder = self.recorder
        figures["recording"] = str(recorder.bag_dir) if recorder is not None else "off"
        figures["live_view"] = f"ws://{self.value['live_view_host']}:{self.live.port}" if self.live is not None else "off"
        failure = recorder.failure if recorder is not None else self._recording_failure
        if self.walk_state in ("fell", "not started") or failure:
            return Report(ERROR, f"{figures['state']}{': recording failed: ' + clip(failure) if failure else ''}", figures)
        if self.walk_state.startswith("waiting"):
            return Report(WARN, self.walk_state, figures)
        return Report(OK, f"{figures['state']}: {figures['touchdowns']} steps, {figures['falls']} falls", figures)

    @property
    def exit_status(self) -> int:
        """0 if the walk finished or was stopped, 1 if it did not finish (see the module)."""
        return 1 if self.failed else 0

    # Waiting -------------------------------------------------------------------------------
    def _wait_until(self, ready, what: str, timeout: float) -> None:
        """Return once ``ready()`` is true, logging every ``LOG_PERIOD`` s what it waits for;
        ``NoPlan`` after ``timeout`` s (0: never) or when the node stops."""
        start = time.monotonic()
        said = start
        while not ready():
            now = time.monotonic()
            if self._stop.is_set() or not self.context.ok():
                raise NoPlan(f"stopped while waiting for {what}")
            if timeout and now - start > timeout:
                raise NoPlan(f"{what}: nothing after {timeout:g} s")
            if now - said >= LOG_PERIOD:
                said = now
                self.get_logger().info(f"waiting for {what} ({now - start:.0f} s)")
            time.sleep(0.002)

    def _answer(self, future, what: str, timeout: float = 120.0):
        """The future's result; ``NoPlan`` after ``timeout`` s or when the node stops."""
        self._wait_until(future.done, f"the answer of {what}", timeout)
        return future.result()

    # Plan acquisition ---------------------------------------------------------------------
    def _on_plan(self, msg: GaitPlan) -> None:
        self._latest_plan = msg
        self._plan_ready.set()

    def _request_plan(self) -> GaitPlan:
        value, patience = self.value, self.value["wait_timeout"]
        mode = MODE_TO_MSG[GaitMode.parse(value["mode"])]
        options = {name: value[name] for name in GAIT_NAMES if name not in ("arm_amplitude", "mode")}
        self.walk_state = "waiting for the planner"
        self._wait_until(self.plan_client.service_is_ready, f"the planner service {value['plan_service']}", patience)
        alpha = value["arm_amplitude"]
        if value["optimize_arms"]:
            self._wait_until(self.optimize_client.server_is_ready,
                             f"the planner's action {value['optimize_action']}", patience)
            low, high = DEFAULTS.arm_range
            goal = OptimizeArmSwing.Goal(mode=mode, alpha_min=low, alpha_max=high, alpha_step=DEFAULTS.arm_coarse_step,
                                         **options)
            handle = self._answer(self.optimize_client.send_goal_async(goal), "optimize_arm_swing")
            result = self._answer(handle.get_result_async(), "optimize_arm_swing").result
            if not result.success:
                raise NoPlan(f"arm-swing optimization failed: {result.message}")
            alpha = result.alpha_opt
            self.get_logger().info(f"optimal arm amplitude {math.degrees(alpha):.2f} deg: {result.message}")
        # the walk needs the plan's boundary states, not its sampled trajectory
        request = PlanGait.Request(arm_amplitude=alpha, mode=mode, omit_trajectory=True,
                                   double_support=value["double_support"], actuated_swing=value["actuated_swing"],
                                   **options)
        # A double support that lasts is an IPOPT solve of tens of seconds (docs/ros.md): waited for once.
        response = (self._call_plan(request, attempts=1, patience=LASTING_PATIENCE) if value["double_support"] > 0.0
                    else self._call_plan(request))
        if not response.success:
            raise NoPlan(f"the planner refused: {response.message}")
        return [response.plan, *response.next_steps]

    def _call_plan(self, request: PlanGait.Request, attempts: int = 5, patience: float = 10.0) -> PlanGait.Response:
        """Call plan_gait, sending again when no answer comes: right after discovery a DDS
        response can be lost (the server has not yet matched our reader; Fast DDS waits 100 ms
        for it, then drops the response). Each new attempt goes through a new client, whose
        endpoints are discovered afresh: a pair of endpoints left unmatched (seen under load in
        CI, no answer to five attempts in 50 s) does not take every attempt with it. The call is
        idempotent (and answered from the planner's cache)."""
        for attempt in range(1, attempts + 1):
            if attempt > 1:
                self._renew_plan_client()
            future = self.plan_client.call_async(request)
            try:
                return self._answer(future, "plan_gait", patience)
            except NoPlan:
                self.plan_client.remove_pending_request(future)
                if self._stop.is_set():
                    raise
            self.get_logger().warn(f"no answer from plan_gait in {patience:g} s (attempt {attempt}/{attempts})")
        raise NoPlan(f"no answer from plan_gait after {attempts} attempts")

    def _renew_plan_client(self) -> None:
        """Replace the plan_gait client by a new one and wait for it to see the service."""
        old, service = self.plan_client, self.value["plan_service"]
        self.plan_client = self.create_client(PlanGait, service, callback_group=self._group)
        self.destroy_client(old)
        self._wait_until(self.plan_client.service_is_ready, f"the planner service {service}", self.value["wait_timeout"])
        settle = time.monotonic() + 1.0  # the server's side of discovery (``ClientSide.connect``)
        self._wait_until(lambda: time.monotonic() > settle, "discovery to settle", 5.0)

    def _obtain_plan(self) -> list[GaitPlan]:
        """The steps of the gait to walk: one, or a stride's two (from the service only)."""
        if self.source == "service":
            return self._request_plan()
        topic = self.value["plan_topic"]
        self.walk_state = "waiting for a plan on the topic"
        self._wait_until(self._plan_ready.is_set, f"a GaitPlan on {topic}", self.value["wait_timeout"])
        return [self._latest_plan]

    def walkable_params(self, name: str) -> str:
        """The parameter set to walk a plan with, from the plan's ``params`` field: a shipped
        set, or this node's own ``params`` file (named by its path or by the name inside it),
        never another path from the wire; ``NoPlan`` otherwise. '' is the default set."""
        if self._own_set is not None and name and names_set(name, self._own_set, self._own_params):
            return self._own_params
        if name == "" or name in shipped_param_names():
            return name
        raise NoPlan(f"the plan's parameter set {clip(repr(name))} is neither a shipped set "
                     f"({', '.join(shipped_param_names())}) nor this simulator's params file: refused")

    # Pushes and speed --------------------------------------------------------------------
    def _on_push(self, request: Push.Request, response: Push.Response) -> Push.Response:
        impulse = [request.impulse.x, request.impulse.y, request.impulse.z]
        wait = 10.0 + (2 * self.value["period"] / self.rtf if self.rtf > 0 else 0.0)  # s: a step or two, and some
        response.success, response.message, response.step, response.time = self.pushes.request(impulse, request.phase, wait)
        self.get_logger().info(f"~/push: {response.message}" if response.success else f"~/push refused: {response.message}")
        return response

    def _before_step(self, walker) -> None:
        """The walker is about to walk a step: its pushes, and a transition towards the commanded speed."""
        self.pushes.before_step(walker)
        self.speed.before_step(walker)

    # The walk -----------------------------------------------------------------------------
    def _engine_text(self) -> str:
        engine = self.value["engine"]
        return f"{engine} (double support of {self.value['pulse_duration'] * 1e3:g} ms)" if engine == "mujoco" else engine

    def _run(self) -> None:
        try:
            if self._recording_failure:
                self._not_started(self._recording_failure)
                return
            try:
                plans = self._obtain_plan()
                params = self.walkable_params(plans[0].params)
            except NoPlan as exc:
                self._not_started(f"no plan: {exc}")
            else:
                self._walk(plans, params)
        except RecordingError as exc:
            self.failed = True
            self.get_logger().error(f"the walk ended: {exc}")
        except Exception as exc:  # noqa: BLE001  reported, and the node stays up for inspection
            if not self._stopping():  # SIGINT/SIGTERM shut the context down under a publish: a stop
                self.failed = True
                self.get_logger().error(f"walk aborted: {clip(repr(exc))}")
        finally:
            if self.value["exit_when_done"]:
                self.exit_requested.set()

    def _stopping(self) -> bool:
        return self._stop.is_set() or not self.context.ok()

    def _not_started(self, reason: str) -> None:
        if self._stopping():
            return
        self.failed = True
        self.walk_state = "not started"
        self.get_logger().error(f"the walk did not start: {clip(reason, 1000)}")
        stamp_ns = self.clock.now_ns()
        self.pub_events.publish(event_msg(GaitEvent.NOT_STARTED, 0, "", 0.0, stamp_msg(stamp_ns), clip(reason, 1000)),
                                stamp_ns)
        self.diagnostics.publish()  # the walk's end, at once

    def _walk(self, plans: list[GaitPlan], params: str) -> None:
        """Walk the gait of ``plans`` (its steps), and again from its start after each reset, until
        the walk ends (with ``exit_when_done``) or the node stops. Simulated time runs on across
        resets."""
        wanted = self.value["wait_for_subscribers"]
        self.walk_state = "waiting for subscribers"
        try:
            self._wait_until(lambda: self.pub_joints.subscription_count() >= wanted,
                             f"{wanted} subscriber(s) of {topics.JOINT_STATES}", self.value["wait_timeout"])
        except NoPlan as exc:
            self._not_started(str(exc))
            return
        try:
            orbit = held_orbit(plans, params)
        except ValueError as exc:  # a plan its walk cannot track (held_support, swing_ends): said, not walked
            self._not_started(str(exc))
            return
        start_ns = self.get_clock().now().nanoseconds
        pacer = Pacer(self.rtf)
        plan = plans[0]
        circle = f", on a circle of radius {plan.turn_radius:g} m" if math.isfinite(plan.turn_radius) else ""
        gait = (f"L = {plan.step_length:g} m, T = {plan.period:g} s, alpha = {math.degrees(plan.arm_amplitude):.2f} deg "
                f"({orbit[0].mode}){circle}")
        duration = self.value["stand_duration"]
        what = (f"standing for {f'{duration:g} s' if duration else 'as long as the node runs'} (the gait to start onto: "
                f"{gait})" if self._standing else f"walking {gait}, {self.steps or 'unlimited'} steps")
        self.get_logger().info(f"{what} at {self.rate:g} Hz, real-time factor {self.rtf:g}, engine {self._engine_text()}")
        try:
            while True:
                self.controls.take_reset()
                self.walk_state = "standing" if self._standing else "walking"
                ended = self._walk_once(orbit, start_ns, pacer)
                if self._stopping() or not ended and not self.controls.reset_requested():
                    return
                if ended:
                    held = time.monotonic()
                    self.pushes.stop("the walk ended")
                    if self.value["exit_when_done"] or not self.controls.wait_for_reset(self._stop):
                        return
                    pacer.delay(time.monotonic() - held)
                self.failed = False
                self.get_logger().info(f"reset: walking again from the plan's start at t = "
                                       f"{self.controls.iterations / self.rate:.3f} s")
        finally:
            self.pushes.stop("the walk ended")

    def _stance_length(self, orbit: PlannedOrbit) -> float:
        """The standing posture's stance length (m): the kept start's where the hybrid engine can start
        onto ``orbit`` with it, else the balance's default (docs/model.md section 13)."""
        start = kept_gait("start")
        if self.value["engine"] == "hybrid" and start is not None and not start.why_not(orbit):
            return start.step_length
        return STANCE_LENGTH

    def _walk_once(self, orbit: tuple[PlannedOrbit, ...], start_ns: int, pacer: Pacer) -> bool:
        """One walk of ``orbit`` from its start, at simulated time ``iterations / rate`` after
        ``start_ns`` (ns); True if it ended (finished or fell, or could not start), False if
        it was stopped or reset."""
        held = time.monotonic()
        steer = self.value["reaim"] and self.value["recovery"] == "momentum" and orbit[0].double_support is None
        walk = Walk(orbit, self.rate, self.steps, reaim=self.value["reaim"],
                    momentum_rate=self.value["momentum_rate"] if steer else None, before_step=self._before_step,
                    engine=self.value["engine"], pulse_duration=self.value["pulse_duration"],
                    initial_state=self.value["initial_state"], stand_duration=self.value["stand_duration"],
                    stance_length=self._stance_length(orbit[0]))
        if walk.world is not None and self._messages is None:
            self._messages = SampleMessages(walk.world.joints.names, walk.world.link_frames)
        if walk.model is not None:
            self._actuated = walk.model.actuated_names
        offset = self.controls.iterations / self.rate  # s of simulated time before this walk
        base_ns = start_ns + round(offset * 1e9)  # the walk's t = 0
        if walk.walker is not None:
            if orbit[0].double_support is None:
                stoppable = self.value["engine"] == "hybrid" and orbit[0].swing_ends is None
                self.speed.start(walk.walker, orbit[0].params or None, base_ns, walk.standing, stoppable)
            else:
                self.get_logger().info("speed command: /cmd_vel is not followed while the walk tracks a double support "
                                       "that lasts: its lift-off posture is far from any other gait's start, whose "
                                       "re-aim does not converge from it (docs/model.md section 14.1)")
            self.pushes.start()
            self.phases.restart()
        pacer.delay(time.monotonic() - held)  # the pacing starts with the walk's first sample
        if walk.world is not None and not self.controls.can_reset:  # the first walk: the latched topics
            self.pub_description.publish(String(data=walk.world.urdf), base_ns)
            self.pub_tf_static.publish(tf_msg(walk.world.static_transforms(), stamp_msg(base_ns)), base_ns)
            self.controls.can_reset = True
        for item in walk.batches():
            if isinstance(item, StepSamples):
                if not self._publish_step(item, base_ns, offset, pacer):
                    return False
            elif isinstance(item, AppliedPush):
                text = f"push of {item.impulse.tolist()} N s on the trunk in step {item.step} at t = {item.t:.4f} s"
                self.stats.count("pushes")
                self.get_logger().info(text)
                self._event(GaitEvent.PUSH, item.step, item.stance_side, item.time_in_step, base_ns, item.t, text)
            elif isinstance(item, Touchdown):
                self.stats.count("touchdowns")
                self._event(GaitEvent.TOUCHDOWN, item.step, item.next_stance_side, item.t_step, base_ns, item.t,
                            f"touchdown of step {item.step}", item)
                self.phases.touchdown(item.step, item.t, base_ns)
            elif isinstance(item, Fell):
                self.speed.end()  # the fall's message is the last
                self.failed = True
                self.walk_state = "fell"
                self.stats.count("falls")
                self.get_logger().error(f"the robot fell in step {item.step}: {item.reason}")
                self._event(GaitEvent.FALL, item.step, item.stance_side, item.time_in_step, base_ns, item.t, item.reason)
                self.diagnostics.publish()
            elif isinstance(item, Finished):
                self.speed.end()
                self.walk_state = "finished"
                done = f"stood {item.t:.3f} s" if walk.standing else f"{item.steps} steps"
                self._event(GaitEvent.FINISHED, item.steps, item.stance_side, 0.0, base_ns, item.t,
                            done if walk.standing else f"walked {done}")
                wall = pacer.elapsed()
                self.get_logger().info(f"walk finished: {done}, {offset + item.t:.3f} s simulated in "
                                       f"{wall:.3f} s wall time (real-time factor {(offset + item.t) / wall:.2f})")
                self.diagnostics.publish()
            elif isinstance(item, CouldNotStart):
                self._not_started(item.reason)
        return True

    # Publishing ---------------------------------------------------------------------------
    def _publish_step(self, step: StepSamples, base_ns: int, offset: float, pacer: Pacer) -> bool:
        """Publish (and show) the samples of one step, each when the pacing releases it, with
        /clock first, then record those published at once; False if stopped or reset before the
        last. The publishers' handles are held for the whole step (``recorded.raw_sender``)."""
        first = step.samples[0]
        t = step.t
        stamps_ns = base_ns + np.round(t * 1e9).astype(np.int64)
        rows = self._messages.encode(step.world, stamps_ns, first.step, first.stance_side)
        publishers = [self.sampled[topic] for topic in rows]
        payloads = [[row.tobytes() for row in encoded] for encoded in rows.values()]
        clock = [row.tobytes() for row in self.clock.encode(stamps_ns)]
        controls, stop, live, paced, sim_clock = self.controls, self._stop, self.live, pacer.factor > 0, self.clock
        if not self.context.ok():  # shut down under us: a stop (the stop flag says so at each sample)
            return False
        recorder, names, encoded = self.recorder, tuple(p.topic for p in publishers), tuple(rows.values())
        published = recorded = 0

        def record() -> None:  # the samples published since the last call; the walk ends if recording failed
            if recorder.failure:
                raise RecordingError(recorder.failure)
            recorder.write_samples(SampleRows(names, tuple(e[recorded:published] for e in encoded),
                                              stamps_ns[recorded:published]))

        try:
            with ExitStack() as handles:
                outputs = [(handles.enter_context(publisher.sending()), data)
                           for publisher, data in zip(publishers, payloads)]
                publish_clock = handles.enter_context(raw_sender(self.clock.publisher))
                for k, (due, stamp) in enumerate(zip((offset + t).tolist(), stamps_ns.tolist())):
                    if controls.paused:
                        held = time.monotonic()
                        controls.hold(stop)
                        pacer.delay(time.monotonic() - held)
                    if controls.reset_requested() or stop.is_set() or paced and not pacer.wait(due, stop):
                        return False
                    publish_clock(clock[k])
                    sim_clock.latest_ns = stamp
                    if k == 0:
                        self.phases.sample(first.step, first.stance_side, first.phase, first.t, base_ns)
                    for send, data in outputs:
                        send(data[k], stamp)
                    if live is not None:
                        live.time(stamp)
                    controls.iterations += 1
                    published = k + 1
                    if recorder is not None and published - recorded == RECORD_EVERY:
                        record()
                        recorded = published
        finally:
            if recorder is not None and published > recorded:
                record()
        return True

    def _event(self, kind: int, step: int, side: str, time_in_step: float, base_ns: int, t: float, message: str,
               touchdown: Touchdown | None = None) -> None:
        stamp_ns = base_ns + round(t * 1e9)
        self.pub_events.publish(event_msg(kind, step, side, time_in_step, stamp_msg(stamp_ns), message, touchdown,
                                          self._actuated), stamp_ns)

    def close(self) -> None:
        """Stop the walk and finalize the recording (shutdown, SIGINT and SIGTERM included);
        ``RecordingError`` if the file could not be finished (the walk then counts as failed)."""
        self._stop.set()
        self._worker.join(timeout=1.5)
        with self._outputs_lock:
            live, recorder = self.live, self.recorder
        if live is not None:
            live.close()
        if recorder is not None:
            try:
                recorder.close()
            except RecordingError:
                self.failed = True
                raise
            if not recorder.failure:
                rclpy.logging.get_logger("biped_gait.recorder").info(f"{self.get_name()}: recording finalized: {recorder.bag_dir}")


def held_orbit(plans: list[GaitPlan], params: str) -> tuple[PlannedOrbit, ...]:
    """The orbit to walk of ``plans`` (its steps) with the parameter set ``params``: with its swing
    actuated at its two ends (``swing_ends.actuated_orbit``) or its double support that lasts
    (``held_support.lasting_orbit``) tracked, when the plan has them; ``ValueError`` for a plan
    whose walk cannot track them."""
    orbit = tuple(replace(orbit_from_msg(plan), params=params) for plan in plans)
    cycle, support = swing_cycle_from_msg(plans[0]), lasting_support_from_msg(plans[0])
    if cycle is None and support is None:
        return orbit
    hybrid = HybridStep(BipedModel.from_params(load_params(params or None)))
    if cycle is not None:
        return (actuated_orbit(orbit[0], cycle, hybrid),)
    return (lasting_orbit(orbit[0], support, hybrid),)


def main(args: list[str] | None = None) -> int:
    """Entry point ``biped-gait-simulator``: walk, publish and record until done or stopped.
    Exit status 1 if the walk did not finish (a fall, no plan, a plan that cannot be walked, a
    recording that failed), 2 for a bad argument or parameter value."""
    usage = Usage("The simulator: walks a plan of the planner, publishing and recording joint states, "
                  "odometry, angular momentum, transforms and gait events.", PARAMETERS)
    return run_node(SimulatorNode, "biped-gait-simulator", args=args, usage=usage)
