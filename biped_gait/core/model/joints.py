"""The biped's joints as data: the joint table of a parameter file, and the model coordinates
derived from it (docs/model.md section 2.1).

A parameter file names the robot's joints (``joints:``), each with its role, its axis, its
parent and child links and its limits. A leg's and an arm's joints are listed once, with
``{side}`` in the name ("right" and "left" on the robot). The roles fix what each joint does:

| role | axis | where |
|---|---|---|
| ``ankle_roll``, ``ankle_pitch`` | x, y | the stance foot's passive pivot (``parent: ground``): no torque, no URDF joint |
| ``hip_pitch``, ``hip_roll``, ``hip_yaw`` | y, x, z | a leg's hip: the pitch alone, or all three in any order from the pelvis |
| ``knee`` | y | thigh to shin |
| ``torso_yaw`` | z | pelvis to trunk |
| ``shoulder`` | y | trunk to arm |

Every joint but the ankles is actuated. The links with mass are the parameter file's ``shin``,
``thigh``, ``trunk`` and ``arm``; every other link (the pelvis, the links between hip joints)
is massless. The model coordinates q follow the single-support tree rooted at the stance foot
(leg 1, the right): the stance ankle (roll, pitch), the stance knee, the stance hip's joints in
reverse order (the chain runs from the thigh up to the pelvis), the torso yaw, the stance-side
then the swing-side shoulder, the swing hip's joints, the swing knee. A coordinate of the stance
leg measures the inverse rotation of its physical joint (its parent and child swap).

Everything that depends on the joints is derived from this table: the Pinocchio models
(``biped``), the leg exchange and the mirror (``exchange``), the URDF (``urdf``), the
double-support configurations, the impulse problem's size and the messages' joint lists.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

ROLE_AXES = {
    "ankle_roll": "x", "ankle_pitch": "y", "hip_pitch": "y", "hip_roll": "x", "hip_yaw": "z", "knee": "y",
    "torso_yaw": "z", "shoulder": "y",
}
ANKLE_ROLES = ("ankle_roll", "ankle_pitch")
HIP_ROLES = ("hip_pitch", "hip_roll", "hip_yaw")
LEG_ROLES = (*HIP_ROLES, "knee")
MASSIVE_LINKS = ("shin", "thigh", "trunk", "arm")
SIDES = ("right", "left")
AXIS_VECTORS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


@dataclass(frozen=True)
class JointLimits:
    """Range (rad), speed (rad/s) and torque (N m) bounds of a joint, for the URDF and the exports."""

    lower: float
    upper: float
    velocity: float
    effort: float


@dataclass(frozen=True)
class JointSpec:
    """One joint of the table: its name (``{side}`` for a leg's or an arm's), role, axis (x, y
    or z of its parent's frame), parent and child links, and limits."""

    name: str
    role: str
    axis: str
    parent: str
    child: str
    limits: JointLimits

    @property
    def paired(self) -> bool:
        """Whether the robot has one on each side (a leg's or an arm's joint)."""
        return "{side}" in self.name

    @property
    def actuated(self) -> bool:
        """Every joint but the stance foot's pivot takes torques (impulses at the double support)."""
        return self.role not in ANKLE_ROLES

    @property
    def lateral(self) -> bool:
        """A rotation about x or z: its angle changes sign in the mirror y -> -y."""
        return self.axis != "y"

    @property
    def leg(self) -> bool:
        return self.role in LEG_ROLES or self.role in ANKLE_ROLES

    def named(self, side: str) -> str:
        """The joint's name on ``side`` of the robot (its URDF name)."""
        return self.name.replace("{side}", side)


@dataclass(frozen=True)
class Coordinate:
    """One coordinate of the single-support model: its name (``stance_knee``, ``swing_hip_roll``,
    ``stance_side_shoulder``, ``torso_yaw``, ...), the table's joint, and the model's side it is
    on (``stance``, ``swing``, or ``""`` for the torso)."""

    name: str
    spec: JointSpec
    side: str

    role = property(lambda self: self.spec.role)
    axis = property(lambda self: self.spec.axis)
    actuated = property(lambda self: self.spec.actuated)
    lateral = property(lambda self: self.spec.lateral)

    @property
    def inverted(self) -> bool:
        """A stance-leg joint: the coordinate is the inverse rotation of the physical joint."""
        return self.side == "stance" and self.spec.role in LEG_ROLES


@dataclass(frozen=True)
class JointTable:
    """The validated joints of a parameter file, in table order."""

    joints: tuple[JointSpec, ...]

    def role(self, role: str) -> JointSpec | None:
        """The joint of ``role``, or None if the table has none."""
        return next((j for j in self.joints if j.role == role), None)

    @property
    def hip_roles(self) -> tuple[str, ...]:
        """The hip's joints, from the pelvis to the thigh (the table's order)."""
        return tuple(j.role for j in self.joints if j.role in HIP_ROLES)

    @property
    def lateral_hips(self) -> bool:
        """Whether the hips have roll or yaw joints: then the legs leave their sagittal planes,
        the leg exchange is no longer linear and the double support needs the old stance foot's
        spin (docs/model.md section 5)."""
        return any(self.role(r) is not None for r in ("hip_roll", "hip_yaw"))

    def coordinates(self) -> tuple[Coordinate, ...]:
        """The single-support model's coordinates q, in order (module docstring)."""
        def leg(role: str, side: str) -> Coordinate:
            spec = self.role(role)
            return Coordinate(spec.named(side), spec, side)

        hips = self.hip_roles
        out = [leg("ankle_roll", "stance"), leg("ankle_pitch", "stance"), leg("knee", "stance")]
        out += [leg(r, "stance") for r in reversed(hips)]
        torso = self.role("torso_yaw")
        shoulder = self.role("shoulder")
        out += [Coordinate(torso.name, torso, ""), Coordinate(shoulder.named("stance_side"), shoulder, "stance"),
                Coordinate(shoulder.named("swing_side"), shoulder, "swing")]
        out += [leg(r, "swing") for r in hips] + [leg("knee", "swing")]
        return tuple(out)

    def physical_joints(self) -> tuple[tuple[JointSpec, str], ...]:
        """The robot's moving joints (the URDF's), as (joint, side): each leg from the hip down,
        right then left, the torso, the shoulders right then left."""
        out = [(self.role(r), side) for side in SIDES for r in (*self.hip_roles, "knee")]
        out.append((self.role("torso_yaw"), ""))
        out += [(self.role("shoulder"), side) for side in SIDES]
        return tuple(out)

    def physical_names(self) -> tuple[str, ...]:
        """The URDF names of ``physical_joints``."""
        return tuple(spec.named(side) if side else spec.name for spec, side in self.physical_joints())


def _default_limits(role: str) -> JointLimits:
    """The limits a joint gets when its entry gives none: the largest ranges a human-like joint
    has (rad; the knee not beyond straight), 30 rad/s, 200 N m; the passive ankle no torque."""
    lower, upper = {
        "ankle_roll": (-0.6, 0.6), "ankle_pitch": (-1.2, 1.2), "hip_pitch": (-2.0, 1.2), "hip_roll": (-0.8, 0.8),
        "hip_yaw": (-0.8, 0.8), "knee": (0.0, 2.5), "torso_yaw": (-1.0, 1.0), "shoulder": (-2.5, 2.5),
    }[role]
    return JointLimits(lower, upper, 30.0, 0.0 if role in ANKLE_ROLES else 200.0)


PAPER_JOINTS = (
    {"name": "{side}_ankle_roll", "role": "ankle_roll", "axis": "x", "parent": "ground", "child": "{side}_ankle"},
    {"name": "{side}_ankle_pitch", "role": "ankle_pitch", "axis": "y", "parent": "{side}_ankle", "child": "shin"},
    {"name": "{side}_hip", "role": "hip_pitch", "axis": "y", "parent": "pelvis", "child": "thigh"},
    {"name": "{side}_knee", "role": "knee", "axis": "y", "parent": "thigh", "child": "shin"},
    {"name": "torso_yaw", "role": "torso_yaw", "axis": "z", "parent": "pelvis", "child": "trunk"},
    {"name": "{side}_shoulder", "role": "shoulder", "axis": "y", "parent": "trunk", "child": "arm"},
)
"""The paper's nine coordinates: the joints of a parameter file that lists none."""


def joint_table(raw: object, source: str) -> JointTable:
    """Build and validate the joint table of a parameter file's ``joints`` list (None: the
    paper's, ``PAPER_JOINTS``). ``ValueError`` with a one-line message when an entry is
    malformed, a role is unknown, missing or repeated, an axis is not its role's, the links do
    not chain (ankle -> shin, pelvis -> hips -> thigh -> knee -> shin, pelvis -> torso -> trunk
    -> shoulder -> arm) or a limit is not a number."""
    entries = PAPER_JOINTS if raw is None else raw
    if not isinstance(entries, (list, tuple)) or not entries:
        raise ValueError(f"parameter file {source}: joints must be a list of joint entries")
    joints = []
    for k, entry in enumerate(entries):
        what = f"parameter file {source}: joints[{k}]"
        if not isinstance(entry, Mapping):
            raise ValueError(f"{what} must be a mapping with name, role, axis, parent and child")
        for key in ("name", "role", "axis", "parent", "child"):
            if not isinstance(entry.get(key), str) or not entry[key]:
                raise ValueError(f"{what}: {key} must be a non-empty string")
        unknown = set(entry) - {"name", "role", "axis", "parent", "child", "lower", "upper", "velocity", "effort"}
        if unknown:
            raise ValueError(f"{what}: unknown key(s) {', '.join(sorted(map(str, unknown)))}")
        role = entry["role"]
        if role not in ROLE_AXES:
            raise ValueError(f"{what}: unknown role {role!r}: use one of {', '.join(ROLE_AXES)}")
        if entry["axis"] != ROLE_AXES[role]:
            raise ValueError(f"{what} ({entry['name']}): a {role} joint turns about {ROLE_AXES[role]}, not "
                             f"{entry['axis']!r}")
        paired = role != "torso_yaw"
        if paired != ("{side}" in entry["name"]):
            raise ValueError(f"{what} ({entry['name']}): " + ("a leg's or an arm's joint names its side as {side}"
                                                                 if paired else "the torso's joint has no {side}"))
        joints.append(JointSpec(entry["name"], role, entry["axis"], entry["parent"], entry["child"],
                                _limits(entry, role, what)))
    table = JointTable(tuple(joints))
    _check_chains(table, source)
    return table


def _limits(entry: Mapping, role: str, what: str) -> JointLimits:
    default = _default_limits(role)
    values = []
    for key in ("lower", "upper", "velocity", "effort"):
        value = entry.get(key, getattr(default, key))
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ValueError(f"{what}: {key} must be a finite number, got {value!r}")
        values.append(float(value))
    limits = JointLimits(*values)
    if not limits.lower < limits.upper or limits.velocity <= 0 or limits.effort < 0:
        raise ValueError(f"{what}: limits must have lower < upper, velocity > 0 and effort >= 0")
    return limits


def _check_chains(table: JointTable, source: str) -> None:
    """Every role once, and the links chained as the model needs them."""
    what = f"parameter file {source}: joints"
    roles = [j.role for j in table.joints]
    for role in set(roles):
        if roles.count(role) > 1:
            raise ValueError(f"{what}: role {role} appears {roles.count(role)} times")
    for role in (*ANKLE_ROLES, "hip_pitch", "knee", "torso_yaw", "shoulder"):
        if role not in roles:
            raise ValueError(f"{what}: no {role} joint (a biped needs {', '.join(r for r in ROLE_AXES if 'hip_' not in r)} and hip_pitch)")
    hips = [j for j in table.joints if j.role in HIP_ROLES]
    if len(hips) == 2:
        raise ValueError(f"{what}: a hip has a pitch joint alone, or a pitch, a roll and a yaw joint, not "
                         f"{' and '.join(j.role for j in hips)}")
    expect = [("ankle_roll", "ground", None), ("ankle_pitch", None, "shin"), ("knee", "thigh", "shin"),
              ("torso_yaw", "pelvis", "trunk"), ("shoulder", "trunk", "arm")]
    parent = "pelvis"
    for k, joint in enumerate(hips):
        expect.append((joint.role, parent, "thigh" if k == len(hips) - 1 else None))
        parent = joint.child
    for role, parent, child in expect:
        joint = table.role(role)
        if parent is not None and joint.parent != parent:
            raise ValueError(f"{what}: {joint.name} must hang on {parent}, not {joint.parent}")
        if child is not None and joint.child != child:
            raise ValueError(f"{what}: {joint.name} must carry {child}, not {joint.child}")
    if table.role("ankle_pitch").parent != table.role("ankle_roll").child:
        raise ValueError(f"{what}: the ankle's pitch must hang on the ankle roll's child link")
    for joint in hips[:-1]:
        if joint.child in MASSIVE_LINKS:
            raise ValueError(f"{what}: {joint.name} must carry a massless link between the hip's joints")
