"""What the exported robot files (URDF, MJCF) add to the model of the planner: epsilon inertias
where the model has none, and collision geometry. The planner's Pinocchio models keep the
paper's values (docs/model.md sections 1 and 9).

The paper's limbs are thin rods, with no inertia about their own axis, and the pelvis and the
links between a hip's joints carry no mass. Pinocchio computes with that; MuJoCo refuses a moving
body whose mass or any principal inertia is not positive ("mass and inertia of moving bodies must
be larger than mjMINVAL", 1e-15). The exports therefore give

- each rod an axial inertia of ``EPSILON_INERTIA`` where the parameter file gives 0,
- each massless moving link (the pelvis, the links between a hip's joints) a mass of
  ``EPSILON_MASS`` at its frame's origin with principal inertias ``EPSILON_INERTIA``.

Bound: they change the mass matrix of the single-support model by at most about
EPSILON_MASS * (2 m)^2 + 8 EPSILON_INERTIA, below 1e-9 kg m^2 against entries of 0.1 to 60 kg m^2
(tested: MuJoCo's mass matrix of the export against the planner's, tests/test_exports.py), and the
ballistic step integrated by MuJoCo from the export follows the plan within 1e-8 rad
(``biped-gait check-mujoco``).

Collision geometry: a capsule along each limb (radius ``LIMB_RADIUS``; the shins' end
``FOOT_CLEARANCE`` short of the foot tips, so that only the feet touch a floor the robot walks
on) and a sphere of radius ``FOOT_RADIUS`` centred at each foot tip: the point foot.
"""

from __future__ import annotations

from .params import Link

EPSILON_MASS = 1e-10
"""kg: the mass an export gives a massless moving link (the pelvis, the links between a hip's joints)."""
EPSILON_INERTIA = 1e-10
"""kg m^2: a principal inertia an export gives where the model has zero (a rod's about its own axis)."""
LIMB_RADIUS = 0.035  # m, the collision and visual capsules of the limbs
FOOT_RADIUS = 0.001  # m, the foot's contact sphere around the tip
FOOT_CLEARANCE = 0.05  # m between a shin capsule's lowest point and its foot tip


def padded_inertia(link: Link) -> tuple[float, float, float]:
    """(Ixx, Iyy, Izz) of ``link`` about its CoM (kg m^2), a zero raised to ``EPSILON_INERTIA``."""
    return tuple(value if value > 0 else EPSILON_INERTIA for value in link.inertia)


def padded(names: list[str], padded_inertias: list[str]) -> str:
    """The one-line statement of what was padded, for the exported file's comment."""
    return (f"epsilon inertias (not in the planner's model): mass {EPSILON_MASS:g} kg and principal inertias "
            f"{EPSILON_INERTIA:g} kg m^2 on the massless links {', '.join(names) or 'none'}; axial inertia "
            f"{EPSILON_INERTIA:g} kg m^2 on the rods {', '.join(padded_inertias) or 'none'}")
