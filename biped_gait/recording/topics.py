"""The names, types and constants of what the project publishes and records, in one place for
the nodes, the recorder and the offline readers (which import no ROS code).

The constants repeat those of the interface definitions in ``msg_defs/`` (a test checks that
they agree with the generated ROS types).
"""

from __future__ import annotations

from enum import IntEnum

from ..core.gait.configurations import GaitMode

JOINT_STATES = "/joint_states"
ODOM = "/odom"
ANGULAR_MOMENTUM = "/angular_momentum"
GAIT_EVENTS = "/gait_events"
ROBOT_DESCRIPTION = "/robot_description"
TF = "/tf"
TF_STATIC = "/tf_static"
GAIT_PHASE = "/gait_phase"
CMD_VEL = "/cmd_vel"  # subscribed: the commanded walking speed and turn
VELOCITY_ENVELOPE = "~/velocity_envelope"  # the simulator's: the commands it walks (latched)
CLOCK = "/clock"  # published, not recorded (ros/sim_clock.py)
ITERATIONS = "~/iterations"  # the simulator's step counter (latched)

RECORD_DIR = "bags"  # the nodes' default record_dir

GAIT_PLAN_TYPE = "biped_gait_interfaces/msg/GaitPlan"
PLAN_CALL_TYPE = "biped_gait_interfaces/msg/PlanGaitCall"
TF_TYPE = "tf2_msgs/msg/TFMessage"


class EventKind(IntEnum):
    """``GaitEvent.kind`` (msg_defs GaitEvent.msg)."""

    TOUCHDOWN = 0
    FALL = 1
    FINISHED = 2
    NOT_STARTED = 3
    PUSH = 4


# PlanGait NORMAL / ANTI_NORMAL (msg_defs PlanGait.srv) and the core's modes.
MODE_CODES = {0: GaitMode.NORMAL, 1: GaitMode.ANTI_NORMAL}
MODE_NAMES = {code: mode.value for code, mode in MODE_CODES.items()}
