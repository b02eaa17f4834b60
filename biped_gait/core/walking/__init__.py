"""Walking gaits step after step: the walker (the hybrid system run from the actual state, the
per-step re-aim), momentum steering, pushes on the trunk, the speed rules and transition steps
of a speed command, the robot in the world frame, and real-time pacing.

Imports ``core.model``, ``core.dynamics`` and ``core.gait``.
"""
