"""``biped-gait atlas``: build, show and check gait atlases (``core.gait.atlas``).

- ``atlas build [--params NAME|FILE] [--mode M ...] [--out DIR] [--workers N | --scheduler ADDR]``:
  build by continuation (``studies.atlas_build``), with a progress bar; written where the
  planner looks for it (package data for a shipped set, the cache for a file) unless ``--out``.
- ``atlas show [--params NAME|FILE] [--mode M ...]``: where each atlas is, whether it is
  current, its nodes per status.
- ``atlas check``: every shipped atlas is current (exit status 1 if one is not).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .core.gait.atlas import Atlas, AtlasError, Grid, atlas_path, rebuild_command
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
    from tqdm import tqdm  # the build's own imports, here: the other verbs and --help do without them

    from .studies.atlas_build import build_atlas
    from .studies.executors import open_executor

    for mode in modes:
        path = args.out / f"{params.name}-{mode.value}.npz" if args.out else atlas_path(params, mode)
        nodes = Grid.default().shape
        with open_executor(args.workers, args.scheduler) as executor, tqdm(
            total=nodes[0] * nodes[1] * nodes[2], unit="gait", desc=f"atlas {params.name} {mode.value}", file=sys.stderr
        ) as bar:
            atlas = build_atlas(params, mode, executor, on_slab=bar.update)
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
    stale = []
    for name in shipped_param_names():
        params = load_params(name)
        for mode in GaitMode:
            try:
                Atlas.load(atlas_path(params, mode), params, name)
            except AtlasError as exc:
                stale.append(str(exc))
    for line in stale:
        print(f"biped-gait: {line}", file=sys.stderr)
    if not stale:
        print(f"every shipped atlas is current ({len(shipped_param_names()) * len(GaitMode)} files); "
              f"rebuild one with `{rebuild_command('NAME')}`")
    return 1 if stale else 0
