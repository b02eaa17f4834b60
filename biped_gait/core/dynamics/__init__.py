"""The biped's equations of motion and their solvers: the ballistic flow (fixed-grid RK8 with
variational equations, and its compiled twin in ``native/``), many sampled states evaluated at
once, the hybrid step (flow, touchdown guard, impact map), the double support's impulse programs
(LP by HiGHS, QP by OSQP), the Newton/chord solver, and the numerical settings.

Imports ``core.model`` only.
"""
