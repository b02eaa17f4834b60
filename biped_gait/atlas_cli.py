"""``biped-gait atlas``: build, show and check gait atlases (``core.gait.atlas``).

- ``atlas build [--params NAME|FILE] [--mode M ...] [--turning] [--out DIR] [--workers N | --scheduler ADDR]``:
  build by continuation (``studies.atlas_build``; ``--turning``: the turning atlas of the
  strides on circles, ``studies.turning_atlas_build``, for a set with lateral hip joints), with a
  progress bar; written where the planner looks for it (package data for a shipped set, the
  cache for a file) unless ``--out``.
- ``atlas show [--params NAME|FILE] [--mode M ...]``: where each atlas is, whether it is
  current, its nodes per status.
- ``atlas check``: every shipped atlas is current, the turning atlases of the sets with
  lateral hip joints included (exit status 1 if one is not).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .core.gait.atlas import Atlas, AtlasError, Grid, atlas_path, rebuild_command
from .core.gait.turning_atlas import TurningAtlas, TurningGrid, turning_atlas_path
from .core.gait.configurations import GaitMode
from .core.model.params import DEFAULT_PARAMS, load_params, shipped_param_names

MODES = [m.value for m in GaitMode]


def add_parser(sub, add_executor) -> None:
    """The ``atlas`` subcommand and its verbs, on the ``biped-gait`` parser's subparsers ``sub``."""
    atlas = sub.add_parser("atlas", help="build, show or check the gait atlases the planner starts from")
    verbs = atlas.add_subparsers(dest="verb", required=True)
    build = verbs.add_parser("build", help="build an atlas by continuation (minutes on 2 cores)")
    show = verbs.add_parser("show", help="where an atlas is, whether it is current, its nodes")
    verbs.add_parser("check", help="check that every shipped atlas is current (exit 1 if not)")
    for verb in (build, show):
        verb.add_argument("--params", default=DEFAULT_PARAMS,
                          help=f"parameter set ({', '.join(shipped_param_names())}) or YAML file")
        verb.add_argument("--mode", nargs="+", choices=MODES, default=MODES, help="gait modes, default both")
    build.add_argument("--turning", action="store_true",
                       help="build the turning atlas (strides on circles; sets with hip roll and yaw joints)")
    build.add_argument("--out", type=Path, metavar="DIR",
                       help="write NAME-MODE.npz here instead of where the planner looks")
    add_executor(build)


def run(args: argparse.Namespace) -> int:
    """Run ``biped-gait atlas VERB``; returns the exit status."""
    if args.verb == "check":
        return _check()
    params = load_params(args.params)
    modes = [GaitMode.parse(m) for m in args.mode]
    if args.verb == "show":
        for mode in modes:
            print(_describe(params, mode, args.params))
        return 0
    if args.turning and not params.joints.lateral_hips:
        print(f"biped-gait: parameter set {params.name} walks straight only: a turning atlas needs hip roll and yaw "
              "joints (e.g. aoustin2013-hips)", file=sys.stderr)
        return 2
    import numpy as np  # the build's own imports, here: the other verbs and --help do without them
    from tqdm import tqdm

    from .studies.atlas_build import build_atlas
    from .studies.executors import open_executor
    from .studies.turning_atlas_build import build_turning_atlas

    for mode in modes:
        kind = "-turning" if args.turning else ""
        where = turning_atlas_path if args.turning else atlas_path
        path = args.out / f"{params.name}-{mode.value}{kind}.npz" if args.out else where(params, mode)
        build = build_turning_atlas if args.turning else build_atlas
        nodes = int(np.prod((TurningGrid if args.turning else Grid).default().shape))
        with open_executor(args.workers, args.scheduler) as executor, tqdm(
            total=nodes, unit="gait", desc=f"atlas {params.name} {mode.value}{kind}", file=sys.stderr
        ) as bar:
            atlas = build(params, mode, executor, on_slab=bar.update)
        atlas.save(path)
        counts = ", ".join(f"{n} {status.replace('_', ' ')}" for status, n in atlas.counts().items())
        print(f"atlas {params.name} {mode.value}: {counts}; built in {atlas.build_seconds:.0f} s; "
              f"{path} ({path.stat().st_size / 1e6:.2f} MB)")
    return 0


def _describe(params, mode: GaitMode, source: str) -> str:
    path = atlas_path(params, mode)
    try:
        atlas = Atlas.load(path, params, source)
    except AtlasError as exc:
        return f"{params.name} {mode.value}: {exc}"
    counts = ", ".join(f"{n} {status.replace('_', ' ')}" for status, n in atlas.counts().items())
    return f"{params.name} {mode.value}: current, {path}; {counts}; built in {atlas.build_seconds:.0f} s"


def _check() -> int:
    stale, files = [], 0
    for name in shipped_param_names():
        params = load_params(name)
        kinds = [(Atlas, atlas_path)] + ([(TurningAtlas, turning_atlas_path)] if params.joints.lateral_hips else [])
        for mode in GaitMode:
            for kind, where in kinds:
                files += 1
                try:
                    kind.load(where(params, mode), params, name)
                except AtlasError as exc:
                    stale.append(str(exc))
    for line in stale:
        print(f"biped-gait: {line}", file=sys.stderr)
    if not stale:
        print(f"every shipped atlas is current ({files} files); rebuild one with `{rebuild_command('NAME')}`")
    return 1 if stale else 0
