"""What integrates the walk's phases (``engine.Engine``): the planner's own model (``hybrid``) and
MuJoCo (``mujoco``)."""
