"""``biped-gait sweep``: a grid of gaits solved by continuation into CSV, JSON and PNG files;
``--json`` the sweep's document as well. Ctrl-C keeps the gaits solved (exit status 130)."""

from __future__ import annotations

import argparse
import sys

from tqdm import tqdm

from ..arguments import check_output_folder, point_values, request_fields
from ..core.model.params import load_params
from ..gait_options import ALPHA_RANGE_DEG
from ..studies.executors import open_executor
from ..studies.figures import sweep_figures
from ..studies.sweep import SweepGrid, solve_grid
from ..studies.sweep_output import SweepFiles, remove_previous
from ..cli import INTERRUPTED
from .output import check_json, write_json


def run(args: argparse.Namespace) -> int:
    grid = SweepGrid.build(
        load_params(args.params),
        point_values(args, "step_length"),
        point_values(args, "period"),
        point_values(args, "arm_amplitude", ALPHA_RANGE_DEG),
        args.mode,
        confirmed=args.yes,
        options=request_fields(args, exclude=("mode", "params")),
    )
    check_json(args.json)
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
    write_json(args.json, files.document())
    converged = sum(r.converged for r in results)
    admissible = sum(r.admissible for r in results)
    print(f"{len(results)} gaits ({converged} converged, {admissible} admissible) written to {files.csv_path} "
          f"and {files.json_path}; {len(figures)} figures in {args.out}")
    return 0
