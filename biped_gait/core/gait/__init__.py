"""One periodic gait and families of gaits: gait modes and boundary configurations, the shooting
boundary-value problem with its closure, the step's figures and the verdict on it, the ``Gait``
and its views (JSON, summary, field list), continuation, the planner, chains of gaits over the
arm amplitude and the amplitude of least effort, the gait atlas and what it is tied to, and the
stability of a gait (its Floquet multipliers).

Imports ``core.model`` and ``core.dynamics``.
"""
