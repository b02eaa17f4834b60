"""The physics core of biped_gait: pure Python over Pinocchio, SciPy, HiGHS and OSQP, no ROS.

Four floors, each importing only the floors below it:

- ``model``: the biped as data (parameter files, the Pinocchio models, the URDF);
- ``dynamics``: its equations of motion and their solvers (the ballistic flow, sampled states,
  the hybrid step, the impulse programs, Newton's method, the numerical settings);
- ``gait``: one periodic gait and families of them (boundary configurations, the shooting BVP,
  figures and verdict, the planner, the atlas, stability);
- ``walking``: walking gaits step after step (the walker, steering, pushes, speed commands,
  the world view, pacing).

``data`` holds the shipped parameter sets and atlases (package data, no code).
"""
