"""``biped-gait maps``: where walking is possible for one mode with the gait options (the
atlas's region seen through the margins, the lowest period, alpha* and W*, the other mode's cost
ratio) as PNG files and a short reading; ``--json`` the maps' numbers."""

from __future__ import annotations

import argparse

from ..arguments import alpha_range, check_output_folder, request_fields
from ..core.model.params import load_params
from ..studies.executors import open_executor
from ..studies.figures import save
from ..studies.maps import CATEGORIES, WalkingMaps, compute_maps, reading
from ..studies.results_page import maps_figures
from .output import check_json, write_json


def document(maps: WalkingMaps) -> dict:
    """The maps' numbers: the region's category per (L, T) node, the boundary, the optima (on one
    atlas node in ``optima_stride`` along L and T)."""
    return {"params": maps.params, "mode": str(maps.mode), "margins": maps.margins,
            "step_lengths": maps.step_lengths, "periods": maps.periods,
            "region": [[CATEGORIES[c] for c in row] for row in maps.region.tolist()],
            "boundary": [{"step_length": length, "min_period": period} for length, period in maps.boundary],
            "optima_stride": maps.stride,
            "optima": [{"step_length": o.step_length, "period": o.period, "alpha": o.alpha, "W": o.W,
                        "other_mode_W": o.other_W, "interior": o.interior} for o in maps.optima]}


def run(args: argparse.Namespace) -> int:
    params = load_params(args.params)
    low, high, step = alpha_range(args)
    check_json(args.json)
    check_output_folder(args.out, "--out", force=True)
    with open_executor(args.workers, args.scheduler) as executor:
        maps = compute_maps(params, executor, coarse_step=step, alpha_range=(low, high),
                            options=request_fields(args, ("mode", "params")), mode=args.mode)
    paths = [save(fig, args.out / name) for fig, name in maps_figures(maps).values()]
    print("\n".join(reading(maps)))
    write_json(args.json, document(maps))
    print("written: " + ", ".join(str(p) for p in paths))
    return 0
