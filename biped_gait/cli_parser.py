"""The parsers of ``biped-gait``: every verb with its arguments, built from the gait vocabulary
(``gait_options``) and nothing heavy, so that ``--help``, a bad argument and the CLI reference
(``docs/cli.md``, ``cli_reference``) need no solver. Each verb names the function that runs it
(``run``: ``module:function``, imported when the verb runs).

Which axis of the gait's point a verb takes, and how, is the verb's; the gait options are the
same on every verb that solves gaits (``GAIT_VERBS``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .arguments import MANY, RANGE, OneLineParser, add_gait_options, add_json, add_point
from .core.model.params import DEFAULT_PARAMS, shipped_param_names
from .gait_options import MODES

PROG = "biped-gait"
DESCRIPTION = ("Ballistic walking gaits of a 3D seven-link biped with swinging arms (Aoustin & Formal'skii): periodic "
               "single support and minimum-effort impulsive double support.")
GAIT_VERBS = ("plan", "sweep", "optimize-arms", "maps", "push-study", "figure", "atlas build", "check-mujoco")
MAX_CASES = 2000  # a larger sweep must be confirmed (--yes); studies.sweep checks it
PUSH_DIRECTIONS = ("forward", "forward-left", "left", "backward-left", "backward", "backward-right", "right",
                   "forward-right")
PUSH_PHASE = 0.5  # fraction of T: mid-step
MOMENTUM_RATE = 0.25  # the walker's momentum steering rate (core.walking.steering.DEFAULT_RATE)
MAP_STRIDE = 2  # the maps' optima on every other atlas node (studies.maps.MAP_STRIDE)


def _run(parser: argparse.ArgumentParser, target: str) -> None:
    parser.set_defaults(run=f"biped_gait.commands.{target}")


def _executor(parser: argparse.ArgumentParser) -> None:
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--workers", type=int, help="local worker processes (default: one per CPU; at most the CPUs)")
    group.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on this Dask distributed scheduler (e.g. tcp://127.0.0.1:8786) instead")


def _plan(sub) -> None:
    plan = sub.add_parser("plan", help="solve one periodic gait and print its summary",
                          description="Solve one periodic gait (on the human-like branch, from the gait atlas) and "
                          "print its summary; exit status 1 if it is not admissible (its reasons are printed).")
    add_point(plan)
    add_gait_options(plan)
    add_json(plan, "the full result (every figure and the sampled step)")
    plan.add_argument("--double-support", type=float, default=0.0, metavar="S",
                      help="a double support that lasts S seconds between the paper's two impulses, with finite "
                      "torques (solved by IPOPT; straight gaits); default 0, the paper's instantaneous one")
    plan.add_argument("--actuated-swing", type=float, default=0.0, metavar="S",
                      help="the swing actuated for its first and last S seconds, with torques within the joints' "
                      "effort limits, and ballistic between, in place of the impulses (the least-effort cycle, "
                      "solved by IPOPT; the simulator walks the variant the planner node serves, "
                      "docs/ros.md); default 0, the impulses")
    plan.add_argument("--start-stop", action="store_true",
                      help="also the gait's start from standing and its stop to standing, each a double support of "
                      "2 s within the joints' effort limits (the package keeps the default gait's; another gait's "
                      "is refused with the reason; docs/model.md 14.2, 14.3)")
    plan.add_argument("--out", type=Path, metavar="DIR", help="write plan.json and plan.png (the step: the biped from "
                      "the side, joint angles, ground reaction and friction ratio, yaw momentum) in this folder")
    _run(plan, "plan:run")


def _sweep(sub) -> None:
    sweep = sub.add_parser("sweep", help="solve a grid of gaits (L, T, alpha, mode) into CSV, JSON and PNG files",
                           description="Solve every gait of a grid, by continuation along alpha; failed and "
                           "inadmissible gaits are kept (marked). Ctrl-C keeps the gaits solved (exit status 130).")
    add_point(sweep, MANY, MANY, MANY, alpha_default="the range 0 45 1.5")
    add_gait_options(sweep, modes=MANY)
    sweep.add_argument("--out", type=Path, default=Path("sweep-results"), metavar="DIR",
                       help="output folder (sweep.csv, sweep.json, W_vs_*.png), default sweep-results; it must be "
                       "empty unless --force")
    add_json(sweep, "the sweep (its grid and every gait, as sweep.json)")
    sweep.add_argument("--force", action="store_true", help="write into a non-empty --out folder, replacing the files "
                       "of an earlier sweep there")
    _executor(sweep)
    sweep.add_argument("--yes", action="store_true", help=f"run a sweep of more than {MAX_CASES} gaits")
    _run(sweep, "sweep:run")


def _optimize(sub) -> None:
    optimize = sub.add_parser("optimize-arms", help="the arm amplitude of least effort W for one (L, T, mode)",
                              description="The arm amplitude of least effort W: a coarse sweep over the range every "
                              "STEP, then a bounded refinement; says when W has no interior minimum on the range.")
    add_point(optimize, alpha=RANGE)
    add_gait_options(optimize)
    add_json(optimize, "the optimum and every amplitude solved")
    optimize.add_argument("--out", type=Path, metavar="DIR",
                          help="write optimum.json and W_vs_alpha.png (every amplitude solved, the optimum marked)")
    _run(optimize, "optimize:run")


def _figure(sub) -> None:
    figure = sub.add_parser("figure", help="draw one of the paper's figures as PNG")
    figure.add_argument("name", choices=("fig4", "fig5"),
                        help="fig4: W against alpha for L = 0.40, 0.45, 0.50 m (T = 0.45 s), both modes, the optima of "
                        "--mode marked; fig5: yaw angular momentum over two steps, L = T = 0.45, both modes at the "
                        "optimal alpha of --mode")
    add_point(figure, step_length=None, period=None, alpha=RANGE)
    add_gait_options(figure)
    figure.add_argument("--out", type=Path, metavar="FILE", help="PNG file, default NAME.png")
    add_json(figure, "the figure's numbers")
    _executor(figure)
    _run(figure, "figure:run")


def _maps(sub) -> None:
    maps = sub.add_parser("maps", help="draw where walking is possible: the admissible region, alpha* and W*, "
                          "the other mode's cost ratio",
                          description="Maps over the atlas's (L, T) grid for one mode: the region where a gait is "
                          "admissible at some alpha (the atlas's nodes, filtered by the margins), the lowest admissible "
                          "period, the optimal amplitude alpha* and its W*, the other mode's W at alpha* over W*.")
    add_point(maps, step_length=None, period=None, alpha=RANGE)
    add_gait_options(maps)
    maps.add_argument("--out", type=Path, default=Path("maps"), metavar="DIR", help="folder of the PNG files, default maps")
    add_json(maps, "the maps' numbers")
    _executor(maps)
    _run(maps, "maps:run")


def _push(sub) -> None:
    push = sub.add_parser("push-study", help="the largest push on the trunk recovered, per direction and arm amplitude "
                          "(bisection), with a polar plot")
    add_point(push, alpha=MANY, alpha_default="0 and the optimal one")
    add_gait_options(push)
    push.add_argument("--directions", nargs="+", default=list(PUSH_DIRECTIONS), choices=PUSH_DIRECTIONS, metavar="NAME",
                      help=f"push directions, default all: {', '.join(PUSH_DIRECTIONS)}")
    push.add_argument("--phase", type=float, default=PUSH_PHASE,
                      help=f"when in the step, a fraction of T in [0, 1), default {PUSH_PHASE:g}")
    push.add_argument("--momentum-rate", type=float, default=MOMENTUM_RATE,
                      help=f"the walker's momentum steering rate in [0, 1), default {MOMENTUM_RATE:g}; "
                      "negative: the duration-only re-aim")
    push.add_argument("--out", type=Path, default=Path("push-results"), metavar="DIR",
                      help="output folder (push.csv, push.json, push-polar.png, push-vs-alpha.png), default push-results")
    add_json(push, "every largest push with its trials (as push.json)")
    _executor(push)
    _run(push, "push:run")


def _results_page(sub) -> None:
    page = sub.add_parser("results-page", help="compute the study and write the results page with its figures")
    page.add_argument("--out", type=Path, default=Path("docs/results.md"), metavar="FILE",
                      help="the page (figures go beside it), default docs/results.md")
    page.add_argument("--alpha-step", type=float, default=1.5, metavar="DEG",
                      help="spacing of the arm amplitudes of the study's sweeps and brackets (deg), default 1.5")
    page.add_argument("--walk-alpha-step", type=float, default=5.0, metavar="DEG",
                      help="spacing of the arm amplitudes of the walk section's closed loops and largest pushes (deg), "
                      "default 5 (the pushes take about 5 s of CPU time per direction and amplitude)")
    page.add_argument("--map-stride", type=int, default=MAP_STRIDE, metavar="N",
                      help=f"the maps' optima on one atlas node in N along L and T, default {MAP_STRIDE} (every other "
                      "one; each optimum takes about a second of CPU time)")
    page.add_argument("--push-directions", nargs="+", default=list(PUSH_DIRECTIONS), choices=PUSH_DIRECTIONS,
                      metavar="NAME", help="directions of the walk section's largest pushes, default all: "
                      f"{', '.join(PUSH_DIRECTIONS)}")
    page.add_argument("--pulse-durations", type=float, nargs="*", default=[1.0, 2.0, 5.0, 10.0, 20.0, 50.0],
                      metavar="MS", help="durations of the double support walked in MuJoCo (ms), default 1 2 5 10 20 "
                      "50 (none: no such section)")
    _executor(page)
    _run(page, "results_page:run")


def _atlas(sub) -> None:
    atlas = sub.add_parser("atlas", help="build, show or check the gait atlases the planner starts from")
    verbs = atlas.add_subparsers(dest="verb", required=True)
    build = verbs.add_parser("build", help="build an atlas by continuation (minutes on 2 cores)",
                             description="Build the atlases of a parameter set by continuation, written where the "
                             "planner looks for them unless --out. Gait options other than the defaults (the "
                             "statuses depend on them) need --out: the planner's atlas is the defaults'.")
    add_gait_options(build, modes=MANY, mode_default=MODES)
    build.add_argument("--turning", action="store_true",
                       help="build the turning atlas (strides on circles; sets with hip roll and yaw joints)")
    build.add_argument("--out", type=Path, metavar="DIR", help="write NAME-MODE.npz here instead of where the planner looks")
    add_json(build, "each atlas built: its file, node counts and build time")
    _executor(build)
    show = verbs.add_parser("show", help="where an atlas is, whether it is current, its nodes (those within the "
                            "margins, if given)")
    show.add_argument("--params", default=DEFAULT_PARAMS,
                      help=f"parameter set ({', '.join(shipped_param_names())}) or YAML file; default {DEFAULT_PARAMS}")
    show.add_argument("--mode", nargs="+", choices=MODES, default=list(MODES), help="gait modes, default every mode")
    for name in ("min_clearance", "friction_margin"):
        from .gait_options import OPTION_BY_NAME

        option = OPTION_BY_NAME[name]
        show.add_argument(option.cli_flag, type=float, default=option.default, metavar=option.cli_unit.upper() or "V",
                          help=f"count the nodes within this {option.help}")
    verbs.add_parser("check", help="check that every shipped atlas is current, the turning atlases included (exit 1 "
                     "if not)")
    for verb, target in ((build, "build"), (show, "show")):
        _run(verb, f"atlas:{target}")
    _run(verbs.choices["check"], "atlas:check")


def _files(sub) -> None:
    urdf = sub.add_parser("urdf", help="print (or write) the URDF of the biped")
    urdf.add_argument("--params", default=DEFAULT_PARAMS, help="parameter set name or YAML file")
    urdf.add_argument("--out", type=Path, metavar="FILE", help="write to this file instead of standard output")
    _run(urdf, "files:urdf")
    recover = sub.add_parser("recover", help="rebuild a complete MCAP file from a killed recorder's file")
    recover.add_argument("bag", type=Path, help="the recording's .mcap file or its directory")
    recover.add_argument("--out", type=Path, metavar="FILE",
                         help="output .mcap (default: <name>_recovered/<name>_recovered_0.mcap)")
    _run(recover, "files:recover")


def _mujoco(sub) -> None:
    mjcf = sub.add_parser("mjcf", help="print (or write) the MJCF (MuJoCo) model of the biped")
    mjcf.add_argument("--params", default=DEFAULT_PARAMS, help="parameter set name or YAML file")
    mjcf.add_argument("--kind", default="floating", choices=("floating", "stance", "extended"),
                      help="floating: the robot with a free pelvis, motors, floor and point feet (default); "
                      "stance: the single-support tree rooted at the stance foot (the model's coordinates); "
                      "extended: that tree with the stance foot's translation (the double support's coordinates)")
    mjcf.add_argument("--out", type=Path, metavar="FILE", help="write to this file instead of standard output")
    _run(mjcf, "mujoco:mjcf")
    check = sub.add_parser("check-mujoco", help="the planned ballistic step integrated by MuJoCo from the export, "
                           "and the impact equations with MuJoCo's matrices, against the plan")
    add_point(check)
    add_gait_options(check)
    check.add_argument("--timestep", type=float, default=1e-4, help="MuJoCo's RK4 step (s), default 1e-4")
    add_json(check, "the check's figures")
    check.add_argument("--out", type=Path, metavar="DIR", help="write check.json (the check's figures) in this folder")
    _run(check, "mujoco:check")


ADDERS = {"plan": _plan, "sweep": _sweep, "optimize-arms": _optimize, "figure": _figure, "maps": _maps,
          "push-study": _push, "results-page": _results_page, "atlas": _atlas, "urdf": _files, "recover": _files,
          "mjcf": _mujoco, "check-mujoco": _mujoco}
"""Each verb and the function that adds its parser (some add two)."""


def build_parser(verb: str | None = None) -> argparse.ArgumentParser:
    """The ``biped-gait`` parser with every verb, or, for a ``verb`` of ``ADDERS``, with that
    verb's parsers alone (what a run of it parses: the others cost it nothing)."""
    top = OneLineParser(prog=PROG, description=DESCRIPTION)
    sub = top.add_subparsers(dest="command", required=True, metavar="VERB")
    for add in [ADDERS[verb]] if verb in ADDERS else dict.fromkeys(ADDERS.values()):
        add(sub)
    return top
