"""Walking gaits step after step: the walk as a sequence of phases (``phases``: each its motion,
guard and reset) run by one runner (``runner``: the samples, pushes and falls) over an engine that
only integrates (``engines``: the planner's model, MuJoCo), the per-step re-aim (``feedback``),
momentum steering, pushes on the trunk, the speed rules and transition steps of a speed command,
the robot in the world frame, and real-time pacing.

Imports ``core.model``, ``core.dynamics`` and ``core.gait``.
"""
