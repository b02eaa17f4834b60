"""Physical parameters of the seven-link biped: one description, loaded from a YAML file.

Three sets ship with the package (docs/model.md section 1): ``aoustin2013`` (the default, the
paper's table with the arm's transverse inertia corrected to a uniform rod's),
``aoustin2013-table`` (the table verbatim), both with the paper's nine joints, and
``aoustin2013-hips`` (the default set with a roll and a yaw joint in each hip). A user passes a
name, or the path of an edited copy. A file's ``joints`` list is the joint table
(``joints.joint_table``; the paper's joints when it has none). Units are SI: m, kg, kg m^2,
m/s^2, rad.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path

from .joints import JointTable, joint_table
from .text import clip
from .yaml_files import parse_package_yaml, parse_yaml, read_yaml_text

DEFAULT_PARAMS = "aoustin2013"
DEFAULT_FRICTION = 0.5  # Coulomb coefficient of the foot on the floor when a file gives none
LINK_NAMES = ("shin", "thigh", "trunk", "arm")
GEOMETRY_KEYS = ("hip_half_width", "torso_joint_height", "shoulder_half_width", "shoulder_height")


@dataclass(frozen=True)
class Link:
    """One rigid link: z axis along the link, pointing up when the biped stands straight.

    ``com_offset`` is the CoM's distance (m) from the link's upper joint (knee for the shin,
    hip for the thigh, pelvis centre for the trunk, shoulder for the arm); ``inertia`` is
    (Ixx, Iyy, Izz) about the CoM in the link frame (kg m^2).
    """

    length: float
    mass: float
    com_offset: float
    inertia: tuple[float, float, float]


@dataclass(frozen=True)
class BipedParams:
    """The whole biped: four link types (legs and arms come in identical pairs) and geometry (m)."""

    name: str
    gravity: float
    shin: Link
    thigh: Link
    trunk: Link
    arm: Link
    hip_half_width: float
    torso_joint_height: float
    shoulder_half_width: float
    shoulder_height: float
    friction: float = DEFAULT_FRICTION
    joints: JointTable = field(default_factory=lambda: joint_table(None, "<paper>"))

    @property
    def leg_length(self) -> float:
        """l = l_s + l_t (m): hip to foot tip with the knee straight."""
        return self.shin.length + self.thigh.length

    @property
    def hip_spacing(self) -> float:
        """Distance between the hip joints (m), 2 l4: the step width of the paper's gaits."""
        return 2 * self.hip_half_width

    @property
    def total_mass(self) -> float:
        """Mass of the whole biped (kg)."""
        return 2 * (self.shin.mass + self.thigh.mass + self.arm.mass) + self.trunk.mass


def shipped_param_names() -> list[str]:
    """Names of the parameter sets that ship with the package."""
    return sorted(p.name[:-5] for p in resources.files("biped_gait.core.data").iterdir() if p.name.endswith(".yaml"))


def load_params(name_or_path: str | Path | None = None) -> BipedParams:
    """Load a shipped parameter set by name, or a YAML file by path (``None``: the default).

    Raises ``ValueError`` with a one-line message for an unknown name, an unreadable file (one
    larger than ``core.model.yaml_files.MAX_YAML_BYTES``, not UTF-8, or nested too deeply included),
    or missing or non-physical values.
    """
    key = DEFAULT_PARAMS if name_or_path in (None, "") else str(name_or_path)
    if key in shipped_param_names():
        return _shipped_params(key)
    if _is_file(key):
        return params_from_dict(parse_yaml(read_yaml_text(key, "parameter file"), f"parameter file {key}"), key)
    raise ValueError(
        f"unknown parameter set {clip(repr(key))}: give one of {', '.join(shipped_param_names())} or a YAML file path"
    )


def names_set(given: str, params: BipedParams, source: str | None = None) -> bool:
    """True if ``given`` (the ``params`` of a request or a plan) names the parameter set
    ``params``, read from ``source`` (a shipped name or a file's path; None: given as values):
    empty (the holder's own set), ``source`` itself or the same file by another path, the set's
    name, or a shipped name whose values these are (a shipped name names the shipped set, even
    where a file took that name). A set given as a file is thus the same set whether named by its
    path or by its name. A path is compared with ``source``, never read: a holder of one set does
    not load a file it is sent."""
    if given in ("", source):
        return True
    if given in shipped_param_names():
        return _shipped_params(given) == params
    return given == params.name or source is not None and _same_file(given, source)


def _same_file(a: str, b: str) -> bool:
    """True if the paths ``a`` and ``b`` are the same existing file."""
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


@lru_cache(maxsize=None)
def _shipped_params(name: str) -> BipedParams:
    """A shipped parameter set, read once per process (package data; ``BipedParams`` is immutable)."""
    text = resources.files("biped_gait.core.data").joinpath(f"{name}.yaml").read_text()
    return params_from_dict(parse_package_yaml(text), name)


def _is_file(key: str) -> bool:
    """True if ``key`` names a regular file (False for names the OS refuses, e.g. too long)."""
    try:
        return Path(key).is_file()
    except (OSError, ValueError):
        return False


def params_from_dict(raw: object, source: str = "<dict>") -> BipedParams:
    """Build and validate ``BipedParams`` from the structure of a parameter file."""
    if not isinstance(raw, dict):
        raise ValueError(f"parameter file {source}: expected a mapping at the top level")
    links_raw = _require(raw, "links", source)
    geometry = _require(raw, "geometry", source)
    if not isinstance(links_raw, dict) or not isinstance(geometry, dict):
        raise ValueError(f"parameter file {source}: 'links' and 'geometry' must be mappings")
    links = {name: _link(_require(links_raw, name, source, "links."), f"{source}: links.{name}") for name in LINK_NAMES}
    geo = {k: _number(_require(geometry, k, source, "geometry."), f"{source}: geometry.{k}") for k in GEOMETRY_KEYS}
    for k in ("hip_half_width", "shoulder_half_width"):
        if geo[k] <= 0:
            raise ValueError(f"parameter file {source}: geometry.{k} must be positive, got {geo[k]}")
    gravity = _number(raw.get("gravity", 9.81), f"{source}: gravity")
    if gravity <= 0:
        raise ValueError(f"parameter file {source}: gravity must be positive, got {gravity}")
    friction = _friction(raw.get("friction", DEFAULT_FRICTION), f"{source}: friction")
    joints = joint_table(raw.get("joints"), source)
    return BipedParams(name=str(raw.get("name", Path(source).stem)), gravity=gravity, **links, **geo, friction=friction,
                       joints=joints)


def _friction(value: object, what: str) -> float:
    """A friction coefficient: positive, or ``inf`` (written .inf in YAML) for no limit."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value) or not value > 0:
        raise ValueError(f"parameter file {what} must be a positive number or .inf, got {value!r}")
    return float(value)


def _require(mapping: dict, key: str, source: str, prefix: str = "") -> object:
    if key not in mapping:
        raise ValueError(f"parameter file {source}: missing value {prefix}{key}")
    return mapping[key]


def _number(value: object, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"parameter file {what} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"parameter file {what} must be finite, got {value}")
    return float(value)


def _link(raw: object, what: str) -> Link:
    if not isinstance(raw, dict):
        raise ValueError(f"parameter file {what} must be a mapping")
    for key in ("length", "mass", "com_offset", "inertia"):
        if key not in raw:
            raise ValueError(f"parameter file {what}: missing value {key}")
    length = _number(raw["length"], f"{what}.length")
    mass = _number(raw["mass"], f"{what}.mass")
    com = _number(raw["com_offset"], f"{what}.com_offset")
    inertia_raw = raw["inertia"]
    if not isinstance(inertia_raw, (list, tuple)) or len(inertia_raw) != 3:
        raise ValueError(f"parameter file {what}.inertia must be a list [Ixx, Iyy, Izz]")
    ixx, iyy, izz = (_number(v, f"{what}.inertia") for v in inertia_raw)
    if length <= 0:
        raise ValueError(f"parameter file {what}.length must be positive, got {length}")
    if mass <= 0:
        raise ValueError(f"parameter file {what}.mass must be positive, got {mass}")
    if not 0 <= com <= length:
        raise ValueError(f"parameter file {what}.com_offset must lie in [0, length={length}], got {com}")
    # A rigid body's principal moments are non-negative and obey the triangle inequality;
    # zero about a limb's long axis (the paper's thin rods) is the admissible limit.
    tol = 1e-12
    if min(ixx, iyy, izz) < 0 or ixx + iyy < izz - tol or iyy + izz < ixx - tol or izz + ixx < iyy - tol:
        raise ValueError(
            f"parameter file {what}.inertia {[ixx, iyy, izz]} is not physical: it must be positive "
            "semi-definite and satisfy the triangle inequality"
        )
    if ixx + iyy + izz <= 0:
        raise ValueError(f"parameter file {what}.inertia must not be all zero")
    return Link(length=length, mass=mass, com_offset=com, inertia=(ixx, iyy, izz))
