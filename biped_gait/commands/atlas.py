"""``biped-gait atlas``: build, show and check the gait atlases (``core.gait.atlas``).

- ``atlas build [--params NAME|FILE] [--mode M ...] [gait options] [--out DIR] [--json PATH]``:
  build by continuation (``studies.atlas_build``), with a progress bar; written where the
  planner looks for it (package data for a shipped set, the cache for a file) unless ``--out``,
  which gait options other than the defaults need (the nodes' statuses depend on them; the
  planner's atlas is the defaults').
- ``atlas show [--params NAME|FILE] [--mode M ...] [--min-clearance M] [--friction-margin V]``:
  where each atlas is, whether it is current, its nodes per status, and with margins how many
  admissible nodes are within them (nodes filtered, not rebuilt).
- ``atlas build --turning``: the turning atlas of the strides on circles
  (``studies.turning_atlas_build``; a set with hip roll and yaw joints, default options only).
- ``atlas check``: every shipped atlas is current, the turning atlases of the sets with lateral
  hip joints included (exit status 1 if one is not).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
from tqdm import tqdm

from ..arguments import request_fields
from ..core.gait.atlas import Atlas, AtlasError, Grid, atlas_path, rebuild_command
from ..core.gait.turning_atlas import TurningAtlas, TurningGrid, turning_atlas_path
from ..core.gait.configurations import GaitMode
from ..core.gait.margins import Margins
from ..core.gait.planner import GaitRequest, validate_request
from ..core.model.params import load_params, shipped_param_names
from ..gait_options import OPTIONS
from ..studies.atlas_build import build_atlas
from ..studies.turning_atlas_build import build_turning_atlas
from ..studies.executors import open_executor
from .output import check_json, write_json


def _counts(atlas: Atlas) -> str:
    return ", ".join(f"{n} {status.replace('_', ' ')}" for status, n in atlas.counts().items())


def build(args: argparse.Namespace) -> int:
    params = load_params(args.params)
    modes = [GaitMode.parse(m) for m in args.mode]
    fields = request_fields(args, ("mode", "params"))
    defaults = {o.name: o.default for o in OPTIONS}
    options = {name: value for name, value in fields.items() if not _same(value, defaults[name])}
    validate_request(GaitRequest(0.45, 0.45, 0.0, modes[0], **options), params)
    if options and args.out is None:
        raise ValueError(f"an atlas with other gait options than the defaults ({', '.join(options)}) is not the "
                         "planner's: give --out DIR")
    if args.turning and (options or not params.joints.lateral_hips):
        raise ValueError(f"a turning atlas is built for a set with hip roll and yaw joints (e.g. aoustin2013-hips), "
                         f"with the default gait options; {params.name}" + (f" with {', '.join(options)}" if options else
                                                                            " walks straight only"))
    check_json(args.json)
    built = []
    for mode in modes:
        kind = "-turning" if args.turning else ""
        where = turning_atlas_path if args.turning else atlas_path
        path = args.out / f"{params.name}-{mode.value}{kind}.npz" if args.out else where(params, mode)
        nodes = int(np.prod((TurningGrid if args.turning else Grid).default().shape))
        with open_executor(args.workers, args.scheduler) as executor, tqdm(
            total=nodes, unit="gait", desc=f"atlas {params.name} {mode.value}{kind}", file=sys.stderr
        ) as bar:
            if args.turning:
                atlas = build_turning_atlas(params, mode, executor, on_slab=bar.update)
            else:
                atlas = build_atlas(params, mode, executor, on_slab=bar.update, options=options)
        atlas.save(path)
        built.append({"params": params.name, "mode": mode.value, "path": str(path), "counts": atlas.counts(),
                      "build_seconds": atlas.build_seconds, "options": options})
        print(f"atlas {params.name} {mode.value}: {_counts(atlas)}; built in {atlas.build_seconds:.0f} s; "
              f"{path} ({path.stat().st_size / 1e6:.2f} MB)")
    write_json(args.json, built)
    return 0


def _same(value: object, default: object) -> bool:
    """Equal, NaN equal to NaN."""
    return value == default or (value != value and default != default)


def show(args: argparse.Namespace) -> int:
    params = load_params(args.params)
    margins = Margins(args.min_clearance, args.friction_margin)
    validate_request(GaitRequest(0.45, 0.45, 0.0, min_clearance=margins.clearance, friction_margin=margins.friction),
                     params)
    for mode in (GaitMode.parse(m) for m in args.mode):
        print(_describe(params, mode, args.params, margins))
    return 0


def _describe(params, mode: GaitMode, source: str, margins: Margins) -> str:
    path = atlas_path(params, mode)
    try:
        atlas = Atlas.load(path, params, source)
    except AtlasError as exc:
        return f"{params.name} {mode.value}: {exc}"
    line = f"{params.name} {mode.value}: current, {path}; {_counts(atlas)}; built in {atlas.build_seconds:.0f} s"
    if margins:
        within = atlas.within(margins).counts()["admissible"]
        line += f"; within the margins ({margins.text()}): {within} of {atlas.counts()['admissible']} admissible nodes"
    return line


def check(_args: argparse.Namespace) -> int:
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
