"""Command line: ``biped-gait plan`` (one gait, printed and optionally saved as JSON),
``biped-gait urdf`` (the robot description), and the arm-swing study: ``sweep`` (grids of
gaits to CSV, JSON and PNG), ``optimize-arms`` (the arm amplitude of least effort),
``figure`` (the paper's Fig. 4 and Fig. 5) and ``results-page`` (docs/results.md); ``atlas``
(build, show, check the gait atlases the planner starts from, ``atlas_cli``); ``push-study``
(the largest push on the trunk the walker recovers from, per direction and arm amplitude);
``mjcf`` and ``check-mujoco`` (the second engine, ``mujoco_cli``).
Degrees at this edge; SI and radians inside. Each verb imports what only it uses (matplotlib, the
study modules, the MCAP readers, MuJoCo) when it runs, so that ``plan`` and ``--help`` cost about
what importing NumPy, SciPy, Pinocchio and HiGHS does.

Errors in the input print one line on stderr and exit with status 2, output paths included
(checked before any work: a folder that cannot be written, a sweep folder holding an earlier
run without ``--force``); a gait that does not converge or is not admissible is printed with
its reasons and exits with status 1, and so does a write that fails at the end (one line). An
interrupted sweep (Ctrl-C) keeps the gaits it has in its files and exits with status 130.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from . import atlas_cli, mujoco_cli
from .arguments import OneLineParser, check_output_file, check_output_folder
from .core.gait import views
from .core.model.params import DEFAULT_PARAMS, load_params, shipped_param_names
from .core.gait.planner import GaitPlanner, GaitRequest, validate_request
from .core.model.urdf import make_urdf
from .studies.executors import open_executor
from .studies.optimize import ALPHA_RANGE, COARSE_STEP, NoAdmissibleGait, optimal_arm_amplitude
from .studies import push_study
from .studies.sweep import MAX_CASES, SweepGrid, inclusive_range, solve_grid
from .studies.sweep_output import SweepFiles, remove_previous

INTERRUPTED = 130  # exit status after Ctrl-C, as shells report it
STDOUT = "-"  # --json - writes to standard output


def _add_params(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--params", default=DEFAULT_PARAMS, help=f"parameter set ({', '.join(shipped_param_names())}) or YAML file"
    )


def _add_executor(parser: argparse.ArgumentParser) -> None:
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--workers", type=int, help="local worker processes (default: one per CPU; at most the CPUs)")
    group.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on this Dask distributed scheduler (e.g. tcp://127.0.0.1:8786) instead")


def _add_alpha_step(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--alpha-step", type=float, default=math.degrees(COARSE_STEP), metavar="DEG",
                        help=f"spacing of the coarse alpha sweep that brackets the minimum (deg), default "
                        f"{math.degrees(COARSE_STEP):g}")


def _add_axis(parser: argparse.ArgumentParser, flag: str, what: str, default: str) -> None:
    group = parser.add_mutually_exclusive_group()
    group.add_argument(f"--{flag}", nargs="+", type=float, metavar="V", help=f"{what}: values, default {default}")
    group.add_argument(f"--{flag}-range", nargs=3, type=float, metavar=("START", "STOP", "STEP"),
                       help=f"{what}: START to STOP inclusive, every STEP")


def _axis(args: argparse.Namespace, flag: str, what: str) -> tuple[float, ...] | None:
    """The values of an axis given as a list or as a range; None if neither was given."""
    values = getattr(args, flag.replace("-", "_"))
    bounds = getattr(args, flag.replace("-", "_") + "_range")
    return inclusive_range(*bounds, what) if bounds is not None else values


def _study_parsers(sub) -> None:
    sweep = sub.add_parser("sweep", help="solve a grid of gaits (L, T, alpha, mode) into CSV, JSON and PNG files")
    _add_axis(sweep, "step-length", "step length L (m)", "0.45")
    _add_axis(sweep, "period", "step period T (s)", "0.45")
    _add_axis(sweep, "alpha-deg", "arm amplitude alpha (deg)", "the range 0 45 1.5")
    sweep.add_argument("--mode", nargs="+", default=["normal", "anti-normal"], help="gait modes, default both")
    _add_params(sweep)
    sweep.add_argument("--out", type=Path, default=Path("sweep-results"), metavar="DIR",
                       help="output folder (sweep.csv, sweep.json, W_vs_*.png), default sweep-results; it must be "
                       "empty unless --force")
    sweep.add_argument("--force", action="store_true", help="write into a non-empty --out folder, replacing the files "
                       "of an earlier sweep there")
    _add_executor(sweep)
    sweep.add_argument("--yes", action="store_true", help=f"run a sweep of more than {MAX_CASES} gaits")

    optimize = sub.add_parser("optimize-arms", help="the arm amplitude of least effort W for one (L, T, mode)")
    optimize.add_argument("--step-length", type=float, default=0.45, help="step length L (m), default 0.45")
    optimize.add_argument("--period", type=float, default=0.45, help="step period T (s), default 0.45")
    optimize.add_argument("--mode", default="normal", help="normal (default) or anti-normal")
    _add_params(optimize)
    optimize.add_argument("--alpha-range", nargs=2, type=float, default=[math.degrees(a) for a in ALPHA_RANGE],
                          metavar=("LOW", "HIGH"), help="arm amplitudes searched (deg), default 0 45")
    _add_alpha_step(optimize)

    figure = sub.add_parser("figure", help="draw one of the paper's figures as PNG")
    figure.add_argument("name", choices=("fig4", "fig5"),
                        help="fig4: W against alpha for L = 0.40, 0.45, 0.50 m (T = 0.45 s); fig5: yaw angular "
                        "momentum over two steps, L = T = 0.45, the normal gait's optimal alpha")
    figure.add_argument("--out", type=Path, help="PNG file, default NAME.png")
    _add_params(figure)
    _add_alpha_step(figure)
    _add_executor(figure)

    maps = sub.add_parser("maps", help="draw where walking is possible: the admissible region, alpha* and W*, "
                          "the anti-normal cost ratio")
    _add_params(maps)
    maps.add_argument("--out", type=Path, default=Path("maps"), metavar="DIR", help="folder of the PNG files, default maps")
    _add_executor(maps)

    push = sub.add_parser("push-study", help="the largest push on the trunk recovered, per direction and arm amplitude "
                          "(bisection), with a polar plot")
    push.add_argument("--step-length", type=float, default=0.45, help="step length L (m), default 0.45")
    push.add_argument("--period", type=float, default=0.45, help="step period T (s), default 0.45")
    push.add_argument("--mode", default="normal", help="normal (default) or anti-normal")
    _add_params(push)
    push.add_argument("--alpha-deg", nargs="+", type=float, metavar="DEG",
                      help="arm amplitudes (deg), default 0 and the optimal one")
    push.add_argument("--directions", nargs="+", default=list(push_study.STUDY_DIRECTIONS), metavar="NAME",
                      help=f"push directions, default all: {', '.join(push_study.STUDY_DIRECTIONS)}")
    push.add_argument("--phase", type=float, default=push_study.PHASE,
                      help=f"when in the step, a fraction of T in [0, 1), default {push_study.PHASE:g}")
    push.add_argument("--momentum-rate", type=float, default=push_study.DEFAULT_RATE,
                      help=f"the walker's momentum steering rate in [0, 1), default {push_study.DEFAULT_RATE:g}; "
                      "negative: the duration-only re-aim")
    push.add_argument("--out", type=Path, default=Path("push-results"), metavar="DIR",
                      help="output folder (push.csv, push.json, push-polar.png, push-vs-alpha.png), default push-results")
    _add_executor(push)

    page = sub.add_parser("results-page", help="compute the study and write the results page with its figures")
    page.add_argument("--out", type=Path, default=Path("docs/results.md"),
                      help="the page (figures go beside it), default docs/results.md")
    _add_alpha_step(page)
    page.add_argument("--walk-alpha-step", type=float, default=5.0, metavar="DEG",
                      help="spacing of the arm amplitudes of the walk section's closed loops and largest pushes (deg), "
                      "default 5 (the pushes take about 5 s of CPU time per direction and amplitude)")
    _add_executor(page)


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="biped-gait",
        description="Ballistic walking gaits of a 3D seven-link biped with swinging arms "
        "(Aoustin & Formal'skii): periodic single support and minimum-effort impulsive double support.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    plan = sub.add_parser("plan", help="solve one periodic gait and print its summary")
    plan.add_argument("--step-length", type=float, default=0.45, help="step length L (m), default 0.45")
    plan.add_argument("--period", type=float, default=0.45, help="step period T (s), default 0.45")
    plan.add_argument("--arm-amplitude", type=float, default=23.5, help="arm amplitude alpha (deg), default 23.5")
    plan.add_argument("--mode", default="normal", help="normal (arms opposite to legs) or anti-normal")
    plan.add_argument(
        "--params", default=DEFAULT_PARAMS, help=f"parameter set ({', '.join(shipped_param_names())}) or YAML file"
    )
    plan.add_argument("--closure", default="theta", choices=("theta", "slack"),
                      help="theta: solve the trunk pitch for an exact cycle (default); slack: theta = 0 and "
                      "the smallest velocity correction s (paper comparison)")
    plan.add_argument("--effort", default="l1", choices=("l1", "l2"),
                      help="l1: W = sum |I| by LP/HiGHS (default); l2: sum I^2 by OSQP")
    plan.add_argument("--friction", type=float, metavar="MU",
                      help="friction coefficient on the double support's reaction impulses and the step's ground "
                      "reaction (default: the parameter set's; inf: no cone)")
    plan.add_argument("--rate-bound", type=float, default=math.inf, metavar="RAD_S",
                      help="bound on the joint rates between the double support's sub-phases (rad/s), default none")
    plan.add_argument("--effort-coordinates", default="joint", choices=("joint", "absolute"),
                      help="the effort's reading: on joint angles (default, the paper's eq. 12) or on the links' "
                      "absolute angles")
    plan.add_argument("--step-width", type=float, metavar="M",
                      help="distance between the feet (m), default the hips' spacing (0.40 m with the shipped sets); "
                      "another width needs hip roll and yaw joints (--params aoustin2013-hips)")
    plan.add_argument("--turn-radius", type=float, default=math.inf, metavar="M",
                      help="walk on a circle of this radius (m; positive turns left, negative right; default inf: "
                      "straight): a stride of two steps; needs hip roll and yaw joints (--params aoustin2013-hips)")
    plan.add_argument("--json", type=Path, help="write the full result (SI, radians) to this JSON file ('-': "
                      "standard output, the summary then goes to standard error)")
    urdf = sub.add_parser("urdf", help="print (or write) the URDF of the biped")
    urdf.add_argument("--params", default=DEFAULT_PARAMS, help="parameter set name or YAML file")
    urdf.add_argument("--output", type=Path, help="write to this file instead of stdout")
    recover_parser = sub.add_parser("recover", help="rebuild a complete MCAP file from a killed recorder's file")
    recover_parser.add_argument("bag", type=Path, help="the recording's .mcap file or its directory")
    recover_parser.add_argument("--out", type=Path, help="output .mcap (default: <name>_recovered/<name>_recovered_0.mcap)")
    _study_parsers(sub)
    atlas_cli.add_parser(sub, _add_executor)
    mujoco_cli.add_parsers(sub)
    return parser


def _sweep(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from .studies.figures import sweep_figures

    alphas_deg = _axis(args, "alpha-deg", "arm amplitude")
    grid = SweepGrid.build(
        load_params(args.params),
        _axis(args, "step-length", "step length") or (0.45,),
        _axis(args, "period", "period") or (0.45,),
        inclusive_range(*ALPHA_RANGE, COARSE_STEP, "arm amplitude") if alphas_deg is None else
        [math.radians(a) for a in alphas_deg],
        args.mode,
        confirmed=args.yes,
    )
    check_output_folder(args.out, "--out", args.force)
    if args.force:
        remove_previous(args.out)
    files = SweepFiles(args.out, grid)
    try:
        with open_executor(args.workers, args.scheduler) as executor, files, tqdm(
            total=grid.size, unit="gait", desc="sweep", file=sys.stderr
        ) as bar:
            for index, results in solve_grid(grid, executor):
                files.add(index, results)
                bar.update(len(results))
    except KeyboardInterrupt:
        print(f"biped-gait: interrupted: {files.count} of {grid.size} gaits kept in {files.csv_path} and "
              f"{files.json_path}", file=sys.stderr)
        return INTERRUPTED
    results = files.results()
    figures = sweep_figures(results, args.out)
    converged = sum(r.converged for r in results)
    admissible = sum(r.admissible for r in results)
    print(f"{len(results)} gaits ({converged} converged, {admissible} admissible) written to {files.csv_path} "
          f"and {files.json_path}; {len(figures)} figures in {args.out}")
    return 0


def _optimize_arms(args: argparse.Namespace) -> int:
    planner = GaitPlanner(args.params)
    low, high = (math.radians(a) for a in args.alpha_range)
    try:
        optimum = optimal_arm_amplitude(planner, args.step_length, args.period, args.mode, (low, high),
                                        math.radians(args.alpha_step))
    except NoAdmissibleGait as exc:
        print(f"biped-gait: {exc}", file=sys.stderr)
        return 1
    print(optimum.describe())
    print(f"{optimum.evaluations} arm amplitudes solved")
    return 0


def _figure(args: argparse.Namespace) -> int:
    from .studies.figures import save
    from .studies.study import FIG4_CASES, FIG5_CASE, run_study

    params = load_params(args.params)
    fig4 = args.name == "fig4"
    out = args.out or Path(f"{args.name}.png")
    check_output_file(out, "--out")
    with open_executor(args.workers, args.scheduler) as executor:
        [study] = run_study(executor, [params], FIG4_CASES if fig4 else (FIG5_CASE,), curves=fig4,
                            coarse_step=math.radians(args.alpha_step))
    save(study.fig4() if fig4 else study.fig5(), out)
    for comparison in study.comparisons.values():
        print(comparison.normal.describe())
    print(f"{args.name} written to {out}")
    return 0


def _push_study(args: argparse.Namespace) -> int:
    from .studies.figures import save

    params = load_params(args.params)
    validate_request(GaitRequest(args.step_length, args.period, 0.0, args.mode), params)
    if not 0.0 <= args.phase < 1.0:
        raise ValueError(f"--phase must be in [0, 1), got {args.phase:g}")
    steering = None if args.momentum_rate < 0 else args.momentum_rate
    if steering is not None and not steering < 1.0:
        raise ValueError(f"--momentum-rate must be below 1, got {args.momentum_rate:g}")
    check_output_folder(args.out, "--out", force=True)
    push_study.study_cases([], args.directions)  # the names checked before any work

    if args.alpha_deg is None:
        optimum = optimal_arm_amplitude(GaitPlanner(params), args.step_length, args.period, args.mode)
        alphas = [0.0, optimum.alpha]
        print(f"optimal arm amplitude {math.degrees(optimum.alpha):.2f} deg ({optimum.where})")
    else:
        alphas = [math.radians(a) for a in args.alpha_deg]
    cases = push_study.study_cases(alphas, args.directions)
    with open_executor(args.workers, args.scheduler) as executor:
        limits = push_study.run_push_study(executor, params, args.step_length, args.period, args.mode, cases,
                                           args.phase, steering)
    paths = push_study.write_results(limits, args.out)
    title = f"Largest push recovered, L = {args.step_length:g} m, T = {args.period:g} s, phase {args.phase:g} T"
    paths.append(save(push_study.polar_figure(limits, title), args.out / "push-polar.png"))
    if len(alphas) > 1:
        paths.append(save(push_study.limit_vs_alpha_figure(limits, title), args.out / "push-vs-alpha.png"))
    print("\n".join(push_study.describe(limit) for limit in limits))
    print("written: " + ", ".join(str(p) for p in paths))
    return 0


def _results_page(args: argparse.Namespace) -> int:
    from .studies.results_page import write_results_page

    check_output_file(args.out, "--out")
    inclusive_range(0.0, 45.0, args.walk_alpha_step, "--walk-alpha-step's")  # checked before any work
    with open_executor(args.workers, args.scheduler) as executor:
        paths = write_results_page(args.out, executor, math.radians(args.alpha_step), math.radians(args.walk_alpha_step))
    print("written: " + ", ".join(str(p) for p in paths))
    return 0


def _maps(args: argparse.Namespace) -> int:
    from .studies.figures import save
    from .studies.maps import compute_maps, reading
    from .studies.results_page import maps_figures

    params = load_params(args.params)
    with open_executor(args.workers, args.scheduler) as executor:
        maps = compute_maps(params, executor)
    paths = [save(fig, args.out / name) for fig, name in maps_figures(maps).values()]
    print("\n".join(reading(maps)))
    print("written: " + ", ".join(str(p) for p in paths))
    return 0


def _recover(args: argparse.Namespace) -> int:
    from .recording.recover import check_mcap, is_complete, recover

    files = sorted(args.bag.glob("*.mcap")) if args.bag.is_dir() else [args.bag]
    if not files or not files[0].is_file():
        raise ValueError(f"no MCAP file at {args.bag}")
    source = files[0]
    check_mcap(source)
    name = source.stem.removesuffix("_0") + "_recovered"
    out = args.out or source.parent.parent / name / f"{name}_0.mcap"
    check_output_file(out, "--out")
    out.parent.mkdir(parents=True, exist_ok=True)
    count = recover(source, out)
    state = "was complete" if is_complete(source) else "was truncated"
    print(f"{source} {state}; {count} messages written to {out}")
    return 0


STUDY_COMMANDS = {"sweep": _sweep, "optimize-arms": _optimize_arms, "figure": _figure, "results-page": _results_page,
                  "atlas": atlas_cli.run, "maps": _maps, "push-study": _push_study,
                  "recover": _recover, **mujoco_cli.COMMANDS}


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``biped-gait``; returns the process exit status."""
    args = _parser().parse_args(argv)
    try:
        if args.command == "urdf":
            if args.output:
                check_output_file(args.output, "--output")
            text = make_urdf(load_params(args.params))
            if args.output:
                args.output.parent.mkdir(parents=True, exist_ok=True)
                args.output.write_text(text)
            else:
                sys.stdout.write(text)
            return 0
        if args.command in STUDY_COMMANDS:
            return STUDY_COMMANDS[args.command](args)
        to_stdout = args.json is not None and str(args.json) == STDOUT
        if args.json is not None and not to_stdout:
            check_output_file(args.json, "--json")
        planner = GaitPlanner(args.params)
        request = GaitRequest(
            step_length=args.step_length,
            period=args.period,
            arm_amplitude=math.radians(args.arm_amplitude),
            mode=args.mode,
            closure=args.closure,
            effort=args.effort,
            friction=args.friction,
            rate_bound=args.rate_bound,
            effort_coordinates=args.effort_coordinates,
            step_width=args.step_width,
            turn_radius=args.turn_radius,
        )
        if math.isfinite(args.turn_radius):
            result = planner.plan_stride(request)
            summary, to_json = views.stride_summary(result), views.stride_to_json
        else:
            result = planner.plan(request)
            summary, to_json = views.summary(result), views.to_json
    except ValueError as exc:
        print(f"biped-gait: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("biped-gait: interrupted", file=sys.stderr)
        return INTERRUPTED
    except OSError as exc:  # a write at the end failed (disk full, folder removed meanwhile)
        print(f"biped-gait: error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    print(summary, file=sys.stderr if to_stdout else sys.stdout)
    try:
        if to_stdout:
            sys.stdout.write(to_json(result) + "\n")
        elif args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(to_json(result))
            print(f"result written to {args.json}")
    except OSError as exc:
        print(f"biped-gait: error: cannot write {args.json}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    return 0 if result.admissible else 1


if __name__ == "__main__":
    sys.exit(main())
