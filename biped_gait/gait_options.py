"""The gait vocabulary: every option a gait request takes, defined once for every interface that
solves gaits (the ``biped-gait`` verbs, the planner's ``plan_gait`` service and
``optimize_arm_swing`` action, the simulator's parameters).

An option's ``name`` is the field of the core's ``GaitRequest``, of the ``PlanGait`` request and
the ``OptimizeArmSwing`` goal, and the simulator's parameter; the command line spells it
``--name-with-dashes`` (``--alpha-deg`` for the arm amplitude, in degrees there, radians
elsewhere). Values are SI with radians. ``friction`` NaN is the parameter set's coefficient and inf
no friction cone; a bound of inf is none; a margin of 0 is none; a ``step_width`` of NaN is the
hips' spacing and a ``turn_radius`` of inf straight.

**0 means unset** where 0 is not a meaningful value (``unset``): a ROS message field cannot
default to NaN or inf (ros2/rosidl issue 351), so a default-constructed request would otherwise
ask for a frictionless floor or a zero bound. A friction coefficient of 0 is the parameter set's
(no gait walks on a frictionless floor), a joint-rate bound of 0 is none, a step width of 0 the
hips' spacing, a turn radius of 0 straight (as NaN is). ``resolve_unset`` applies it, the same on
every interface (the verbs, the service, the action, the simulator's parameters); NaN and inf
keep their meanings.

``POINT`` holds where a gait is (L, T, alpha: one value, a list or a range, as each verb needs),
``OPTIONS`` how it is solved and judged, ``MARGINS`` the options a gait must meet beyond the
limits (docs/model.md section 4.2). Adding an option is one entry in ``OPTIONS`` plus its field
in ``GaitRequest`` and in the interfaces of ``msg_defs/``; ``tests/test_gait_options.py``
checks that they agree, and every verb and node takes it from here.

Imports nothing heavy (the command line builds its parsers from this module alone).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .core.gait.configurations import GaitMode
from .core.model.params import DEFAULT_PARAMS, shipped_param_names

MODES = tuple(mode.value for mode in GaitMode)
ALPHA_RANGE_DEG = (0.0, 45.0, 1.5)  # the arm amplitudes searched and swept by default: start, stop, step (deg)


@dataclass(frozen=True)
class GaitOption:
    """One option: ``default`` in SI units with radians (``unit``; '' for none), ``help`` a
    phrase saying what it is, ``choices`` for a word, ``flag`` the command line's spelling when
    it is not the name's, ``degrees`` when the command line takes degrees, ``unset`` the value a
    0 stands for where 0 is not a meaningful value (None: 0 is itself)."""

    name: str
    default: float | str
    unit: str
    help: str
    choices: tuple[str, ...] = ()
    flag: str = ""
    degrees: bool = False
    unset: float | None = None

    @property
    def cli_flag(self) -> str:
        """The command line's flag, e.g. ``--rate-bound``."""
        return "--" + (self.flag or self.name.replace("_", "-"))

    @property
    def cli_unit(self) -> str:
        """The unit on the command line."""
        return "deg" if self.degrees else self.unit

    def from_cli(self, value: float | str) -> float | str:
        """A command-line value in the request's units (degrees to radians)."""
        return math.radians(value) if self.degrees else value

    def to_cli(self, value: float | str) -> float | str:
        """A request value in the command line's units (radians to degrees)."""
        return math.degrees(value) if self.degrees else value

    def default_text(self, cli: bool = False) -> str:
        """The default as people read it: the parameter set's value for NaN, none for an
        infinite bound or a zero margin, else the value (in the command line's units if ``cli``)."""
        value = self.to_cli(self.default) if cli else self.default
        if isinstance(value, str):
            return value
        if math.isnan(value):
            return "the hips' spacing" if self.name == "step_width" else "the parameter set's"
        if math.isinf(value) and self.name == "turn_radius":
            return "straight"
        if math.isinf(value) or (self.name in MARGINS and value == 0.0):
            return "none"
        unit = self.cli_unit if cli else self.unit
        return f"{value:g} {unit}".strip()


POINT = (
    GaitOption("step_length", 0.45, "m", "step length L"),
    GaitOption("period", 0.45, "s", "step period T"),
    GaitOption("arm_amplitude", math.radians(23.5), "rad", "arm amplitude alpha", flag="alpha-deg", degrees=True),
)
OPTIONS = (
    GaitOption("mode", GaitMode.NORMAL.value, "", "arm swing: normal (arms opposite to the legs, as people walk) or "
               "anti-normal (each arm with the leg on its side)", choices=MODES),
    GaitOption("params", DEFAULT_PARAMS, "", f"parameter set: a shipped name ({', '.join(shipped_param_names())}) or "
               "the path of a YAML file"),
    GaitOption("closure", "theta", "", "theta: the trunk pitch solved for an exact cycle; slack: theta = 0 and the "
               "smallest velocity correction (the paper's comparison)", choices=("theta", "slack")),
    GaitOption("effort", "l1", "", "l1: W = sum |I| by linear programming (HiGHS); l2: sum I^2 (OSQP)",
               choices=("l1", "l2")),
    GaitOption("effort_coordinates", "joint", "", "the effort's reading: on joint angles (the paper's eq. 12) or on "
               "the links' absolute angles", choices=("joint", "absolute")),
    GaitOption("friction", math.nan, "", "friction coefficient of the floor on the double support's reaction "
               "impulses and the step's ground reaction (0 or NaN: the parameter set's; inf: no cone)", unset=math.nan),
    GaitOption("rate_bound", math.inf, "rad/s", "margin: bound on the joint rates between the double support's "
               "sub-phases (0 or inf: none)", unset=math.inf),
    GaitOption("min_clearance", 0.0, "m", "margin: least swing-tip height above the ground on (0.05 T, 0.95 T)"),
    GaitOption("friction_margin", 0.0, "", "margin: the reaction impulses and the step's ground reaction within "
               "mu - this"),
    GaitOption("step_width", math.nan, "m", "distance between the feet (0 or NaN: the hips' spacing; another needs "
               "hip roll and yaw joints)", unset=math.nan),
    GaitOption("turn_radius", math.inf, "m", "radius of the circle walked, signed: positive turns left (0, NaN or "
               "inf: straight; a finite one is a stride of two steps, planned by plan, with hip roll and yaw joints)",
               unset=math.inf),
)
MARGINS = ("rate_bound", "min_clearance", "friction_margin")
OPTION_BY_NAME = {option.name: option for option in (*POINT, *OPTIONS)}


def resolve_unset(fields: dict[str, object]) -> dict[str, object]:
    """``fields`` (options by name) with each 0 that means unset replaced by the value it stands
    for, and a NaN turn radius by inf (straight); every other value as given."""
    out = dict(fields)
    for name, value in fields.items():
        option = OPTION_BY_NAME.get(name)
        if option is not None and option.unset is not None and isinstance(value, float) and (
                value == 0.0 or (name == "turn_radius" and math.isnan(value))):
            out[name] = option.unset
    return out


def defaults() -> dict[str, float | str]:
    """Every option's default, by name (the point's too)."""
    return {option.name: option.default for option in (*POINT, *OPTIONS)}
