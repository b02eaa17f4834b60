"""Maps of where walking is possible, per parameter set (beyond the paper, which studied three
points): the admissible region in the (L, T) plane with the condition that limits each part of
it, the lowest admissible period at each L, the optimal arm amplitude alpha*(L, T) and its
effort W*(L, T), and the anti-normal / normal cost ratio at alpha*.

The maps are of one gait mode (normal by default; the cost ratio is the other mode's) and take
the gait options: the region comes from that mode's gait atlas (every alpha of the atlas), seen
through the margins asked (``Atlas.within``: nodes filtered, not rebuilt): a node (L, T) is
admissible if the gait is at some alpha; otherwise it is marked with the condition that limits
it at the most alphas, or as meeting the limits but not the margins. The boundary T_min(L) is
found by bisection along T on the human-like branch (at ``BOUNDARY_ALPHA``), the optima by
``arm_optimum.optimal_arm_amplitude`` on one atlas node in ``stride`` along L and T of the
admissible region (every other one by default, ``MAP_STRIDE``), both with the options, in
parallel on an executor.
L in m, T in s, alpha in rad (figures and text in degrees), W in N m s.
"""

from __future__ import annotations

import math
import re
from collections import Counter
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from ..core.gait.admissibility import LIMIT_NAMES, Limit
from ..core.gait.atlas import Atlas, NodeStatus, atlas_path
from ..core.gait.configurations import GaitMode
from ..core.model.params import BipedParams
from ..core.gait.planner import GaitRequest, validate_request
from .executors import planner_for
from ..core.gait.arm_optimum import ALPHA_RANGE, COARSE_STEP, NoAdmissibleGait
from .mode_comparison import compare_modes

BOUNDARY_ALPHA = math.radians(25.0)  # rad: near the optima of the default set
MAP_STRIDE = 2  # the optima on every other atlas node in L and T
ADMISSIBLE = "admissible"
MARGINS_ONLY = "within the limits, not the margins"
TWIN_ONLY = "backward-knee twin only"
CATEGORIES = (ADMISSIBLE, *LIMIT_NAMES.values(), TWIN_ONLY, MARGINS_ONLY)
COLOURS = ("#4daf4a", "#999999", "#a65628", "#e41a1c", "#ff7f00", "#377eb8", "#984ea3", "#ffff33", "#f781bf",
           "#b3de69")
NO_GAIT_COLOUR = "#d9d9d9"  # the stability map's nodes without an admissible gait


@dataclass(frozen=True)
class Optimum:
    """The optimal gait of the maps' mode at (L, T): alpha* (rad), W* (N m s), and the other
    mode's W at alpha* (NaN if that gait is not admissible)."""

    step_length: float
    period: float
    alpha: float
    W: float
    other_W: float
    interior: bool

    @property
    def ratio(self) -> float:
        return self.other_W / self.W


@dataclass(frozen=True, eq=False)
class WalkingMaps:
    """The maps of one parameter set and ``mode``: the region per atlas (L, T) node (category
    names), the boundary (L, T_min) pairs, and the optima on the coarser grid; ``margins``
    names the margins asked ('' if none); the optima are on one atlas node in ``stride`` along
    L and T."""

    params: str
    mode: GaitMode
    margins: str
    step_lengths: np.ndarray
    periods: np.ndarray
    region: np.ndarray  # (L, T): index into CATEGORIES
    boundary: list[tuple[float, float]]
    optima: list[Optimum]
    stride: int

    @property
    def optima_nodes(self) -> str:
        """Which atlas nodes hold the optima, in words."""
        return {1: "every atlas node", 2: "every other atlas node"}.get(
            self.stride, f"one atlas node in {self.stride} along L and T")


def region(atlas: Atlas) -> np.ndarray:
    """Per (L, T) node of ``atlas``: 0 if admissible at some alpha, else the index in
    ``CATEGORIES`` of the condition that limits it at the most alphas (an inadmissible node with
    no limit's condition meets the limits but not the margins ``atlas`` is seen through)."""
    status, limits = atlas.nodes["status"], atlas.nodes["limits"]
    out = np.zeros(status.shape[:2], dtype=int)
    for i, j in np.ndindex(*out.shape):
        if np.any(status[i, j] == NodeStatus.ADMISSIBLE):
            continue
        votes: Counter[str] = Counter()
        for k in range(status.shape[2]):
            if status[i, j, k] == NodeStatus.TWIN_ONLY:
                votes[TWIN_ONLY] += 1
            elif status[i, j, k] == NodeStatus.INADMISSIBLE and limits[i, j, k] == 0:
                votes[MARGINS_ONLY] += 1
            for bit, name in LIMIT_NAMES.items():
                if status[i, j, k] != NodeStatus.TWIN_ONLY and Limit(int(limits[i, j, k])) & bit:
                    votes[name] += 1
        out[i, j] = CATEGORIES.index(votes.most_common(1)[0][0])
    return out


def boundary_period(params: BipedParams, mode: GaitMode, step_length: float, low: float, high: float,
                    alpha: float = BOUNDARY_ALPHA, tol: float = 1e-3, options: Mapping[str, object] | None = None) -> float:
    """The lowest admissible T (s) in [low, high] at L (m) and alpha (rad), by bisection on the
    planner's verdict (``high`` admissible, ``low`` not), to ``tol`` s; ``options``: further
    ``GaitRequest`` fields."""
    planner = planner_for(params)
    while high - low > tol:
        middle = 0.5 * (low + high)
        if planner.plan(GaitRequest(step_length, middle, alpha, mode, **(options or {}))).admissible:
            high = middle
        else:
            low = middle
    return high


def _optimum(params: BipedParams, step_length: float, period: float, coarse_step: float,
             alpha_range: tuple[float, float], options: Mapping[str, object] | None, mode: GaitMode) -> Optimum | None:
    """Worker entry: the optimum of ``mode`` at (L, T) on ``alpha_range`` (rad, bracketed every
    ``coarse_step`` rad) and the other mode's gait there; None if no gait of the range is admissible."""
    try:
        comparison = compare_modes(params, step_length, period, alpha_range, coarse_step, options, mode)
    except NoAdmissibleGait:
        return None
    optimum, other = comparison.optimum, comparison.other
    return Optimum(step_length, period, optimum.alpha, optimum.W, other.W if other.usable else math.nan,
                   optimum.interior)


def compute_maps(params: BipedParams, executor: Executor, stride: int = MAP_STRIDE, coarse_step: float = COARSE_STEP,
                 alpha_range: tuple[float, float] = ALPHA_RANGE, options: Mapping[str, object] | None = None,
                 mode: GaitMode | str = GaitMode.NORMAL) -> WalkingMaps:
    """The maps of ``params`` and ``mode`` from its current atlas seen through the margins of
    ``options`` (further ``GaitRequest`` fields of every gait); optima on every ``stride``-th node
    of the admissible region (``alpha_range`` rad, bracketed every ``coarse_step`` rad), on
    ``executor``. ``ValueError`` for options the planner refuses."""
    mode = GaitMode.parse(mode)
    options = dict(options or {})
    problem = validate_request(GaitRequest(0.45, 0.45, alpha_range[0], mode, **options), params)
    atlas = Atlas.load(atlas_path(params, mode), params)
    if problem.margins:
        atlas = atlas.within(problem.margins, problem.options.friction)
    grid = atlas.grid
    cells = region(atlas)
    boundary_tasks = {}
    for i, length in enumerate(grid.step_lengths):
        row = np.flatnonzero(cells[i] == 0)
        if row.size and row[0] > 0:
            boundary_tasks[float(length)] = executor.submit(
                boundary_period, params, mode, float(length), float(grid.periods[row[0] - 1]),
                float(grid.periods[row[0]]), options=options)
    optimum_tasks = [executor.submit(_optimum, params, float(grid.step_lengths[i]), float(grid.periods[j]), coarse_step,
                                     alpha_range, options, mode)
                     for i in range(0, len(grid.step_lengths), stride) for j in range(0, len(grid.periods), stride)
                     if cells[i, j] == 0]
    boundary = [(length, future.result()) for length, future in boundary_tasks.items()]
    optima = [o for o in (f.result() for f in optimum_tasks) if o is not None]
    return WalkingMaps(params.name, mode, problem.margins.text(problem.options.rate_bound), grid.step_lengths,
                       grid.periods, cells, boundary, optima, stride)


# Figures -------------------------------------------------------------------------------------

def _figure(columns: int = 1) -> tuple[Figure, list]:
    fig = Figure(figsize=(5.2 * columns, 4.4), layout="constrained")
    FigureCanvasAgg(fig)
    return fig, [fig.add_subplot(1, columns, c + 1) for c in range(columns)]


def _edges(values: np.ndarray) -> np.ndarray:
    step = np.diff(values).mean()
    return np.concatenate([values - step / 2, [values[-1] + step / 2]])


def region_figure(maps: WalkingMaps) -> Figure:
    """The admissible region in the (L, T) plane, each node coloured by its limiting condition,
    with the boundary T_min(L) at alpha = 25 deg."""
    fig, [ax] = _figure()
    present = sorted(set(maps.region.ravel().tolist()))
    cmap = ListedColormap(list(COLOURS))
    ax.pcolormesh(_edges(maps.step_lengths), _edges(maps.periods), maps.region.T, cmap=cmap,
                  norm=BoundaryNorm(np.arange(len(CATEGORIES) + 1) - 0.5, len(CATEGORIES)))
    handles = [Patch(color=COLOURS[c], label=CATEGORIES[c]) for c in present]
    if maps.boundary:
        lengths, periods = zip(*maps.boundary)
        (line,) = ax.plot(lengths, periods, "k.-", label=f"lowest admissible T, alpha = {math.degrees(BOUNDARY_ALPHA):g} deg")
        handles.append(line)
    ax.set_xlabel("step length L (m)")
    ax.set_ylabel("period T (s)")
    margins = f"\nmargins: {maps.margins}" if maps.margins else ""
    ax.set_title(f"Where walking is possible, params {maps.params}\n({maps.mode} gait, some alpha in [0, 45] deg)"
                 f"{margins}", fontsize="medium")
    fig.legend(handles=handles, fontsize="small", loc="outside lower center", ncols=2)
    return fig


def file_suffix(maps: WalkingMaps) -> str:
    """What the maps' file names add for their margins ('' if none): '-swing-clearance-5-mm', ..."""
    return "-" + re.sub(r"[^a-z0-9.]+", "-", maps.margins.lower()).strip("-") if maps.margins else ""


def _no_gait(ax, maps: WalkingMaps) -> list[Patch]:
    """The (L, T) cells without an admissible gait (the region map says why) shaded, the others
    white; the legend's handles of both."""
    none = np.pad(np.where(maps.region.T == 0, np.nan, 1.0), 1, mode="edge")  # a cell more around: the end tiles
    lengths, periods = (np.concatenate([[v[0] - np.diff(v).mean()], v, [v[-1] + np.diff(v).mean()]])
                        for v in (maps.step_lengths, maps.periods))
    ax.pcolormesh(_edges(lengths), _edges(periods), none, cmap=ListedColormap([NO_GAIT_COLOUR]), vmin=0.0, vmax=1.0)
    within = " within the margins" if maps.margins else ""
    return [Patch(color=NO_GAIT_COLOUR, label=f"no admissible {maps.mode} gait{within} (the region map says why)"),
            Patch(facecolor="white", edgecolor="#999999", label=f"admissible{within}; optima at {maps.optima_nodes} "
                  "only")]


def _scatter_map(ax, maps: WalkingMaps, values: Sequence[float], label: str, fig: Figure, digits: int = 1,
                 mark_ends: bool = False, missing: str = "", scaled: Sequence[bool] | None = None) -> list:
    """Tiles of ``values`` at the optima's (L, T) (``maps.optima_nodes``), each with its value in
    ``digits`` decimals (as many as the colour bar's range needs to tell the tiles apart), dark
    text on light tiles, over the cells without an admissible gait shaded; a value that is not
    finite is an empty tile marked '-', ``missing`` saying why; ``mark_ends``: outline the tiles
    whose least W is at an end of the alpha range (no interior minimum); ``scaled``: the tiles the
    colour scale spans (None: all), the others coloured at its ends (the colour bar's arrows) so
    that one outlier does not flatten the rest. Returns the legend's handles: the shading, the
    empty tile (if any), the outline (if any)."""
    handles: list = _no_gait(ax, maps)
    lengths = [o.step_length for o in maps.optima]
    periods = [o.period for o in maps.optima]
    spanned = [v for k, v in enumerate(values) if math.isfinite(v) and (scaled is None or scaled[k])]
    low, high = (min(spanned), max(spanned)) if spanned else (None, None)
    points = ax.scatter(lengths, periods, c=values, s=420, marker="s", cmap="viridis", vmin=low, vmax=high)
    for x, y, v in zip(lengths, periods, values):
        red, green, blue, _ = points.cmap(points.norm(v)) if math.isfinite(v) else (1, 1, 1, 1)
        light = 0.299 * red + 0.587 * green + 0.114 * blue > 0.55
        text = f"{v:.{digits}f}" if math.isfinite(v) else "-"
        ax.annotate(text, (x, y), ha="center", va="center", fontsize=7.5 * min(1.0, 4.5 / len(text)),  # in the tile
                    color="black" if light else "white", fontweight="bold")
    empty = [(x, y) for x, y, v in zip(lengths, periods, values) if not math.isfinite(v)]
    if empty:
        handles.append(ax.scatter(*zip(*empty), s=420, marker="s", facecolors="white", edgecolors="#999999",
                                  linewidths=1.0, label=f"- {missing}"))
    ends = [(o.step_length, o.period) for o in maps.optima if not o.interior]
    if mark_ends and ends:
        handles.append(ax.scatter(*zip(*ends), s=420, marker="s", facecolors="none", edgecolors="#e41a1c",
                                  linewidths=1.8, label="least W at an end of the alpha range (no interior minimum)"))
    finite = [v for v in values if math.isfinite(v)]
    below, above = bool(spanned) and min(finite) < low, bool(spanned) and max(finite) > high
    fig.colorbar(points, ax=ax, label=label,
                 extend="both" if below and above else "min" if below else "max" if above else "neither")
    ax.set_xlabel("step length L (m)")
    ax.set_ylabel("period T (s)")
    return handles


def _heading(maps: WalkingMaps) -> str:
    """The maps' mode, parameter set and margins, for a title."""
    return f"{maps.mode} gait, params {maps.params}" + (f", margins: {maps.margins}" if maps.margins else "")


def optimum_figure(maps: WalkingMaps) -> Figure:
    """alpha*(L, T) (deg) and W*(L, T) (N m s) of the maps' mode over the admissible region, the
    tiles without an interior minimum (alpha* at an end of the range) outlined and, where they are
    fewer than the others, left out of the alpha* colour scale (their values written on them)."""
    fig, (left, right) = _figure(2)
    fig.set_size_inches(12.0, 5.6)
    interior = [o.interior for o in maps.optima]
    # alpha* at an end of the range (0 or 45 deg) is no optimum but the range's bound: where such
    # tiles are few, the alpha* scale spans the interior ones, which they would flatten
    scaled = interior if 2 * sum(interior) >= len(interior) else None
    handles = _scatter_map(left, maps, [math.degrees(o.alpha) for o in maps.optima],
                           "optimal arm amplitude alpha* (deg)", fig, mark_ends=True, scaled=scaled)
    _scatter_map(right, maps, [o.W for o in maps.optima], "least effort W* (N m s)", fig, mark_ends=True)
    fig.legend(handles=handles, fontsize="small", loc="outside lower center", ncols=2, markerscale=0.5)
    fig.suptitle(f"The optimal arm swing over the admissible region ({maps.optima_nodes}), {_heading(maps)}",
                 fontsize="medium")
    left.set_title("alpha*(L, T)", fontsize="medium")
    right.set_title("W*(L, T)", fontsize="medium")
    return fig


def ratio_figure(maps: WalkingMaps) -> Figure:
    """W of the other mode's gait over W of the maps' mode, both at the latter's alpha*."""
    other = GaitMode.ANTI_NORMAL if maps.mode is GaitMode.NORMAL else GaitMode.NORMAL
    fig, [ax] = _figure()
    fig.set_size_inches(6.4, 6.0)
    ratios = [o.ratio for o in maps.optima]
    finite = [r for r in ratios if math.isfinite(r)]
    spread = max(finite) - min(finite) if len(finite) > 1 else 0.0
    digits = max(2, math.ceil(-math.log10(spread)) + 1) if spread > 0 else 2  # enough to tell the tiles apart
    handles = _scatter_map(ax, maps, ratios, f"W {other} / W {maps.mode} at alpha*", fig, digits=digits,
                           missing=f"the {other} gait at alpha* is not admissible")
    fig.legend(handles=handles, fontsize="small", loc="outside lower center", markerscale=0.5)
    ax.set_title(f"Cost of the {other} arm swing at the {maps.mode} gait's alpha*\n{_heading(maps)}",
                 fontsize="medium")
    return fig


def stability_figure(atlas: Atlas, alpha: float = BOUNDARY_ALPHA) -> Figure:
    """The open-loop spectral radius of the Poincare map over (L, T), at the atlas alpha nearest
    ``alpha`` (rad), on the admissible nodes (log scale); the nodes without an admissible gait
    (nothing to measure) in grey, as the legend says."""
    fig, [ax] = _figure()
    ax.set_facecolor(NO_GAIT_COLOUR)
    k = int(np.argmin(np.abs(atlas.grid.alphas - alpha)))
    radius = np.where(atlas.nodes["status"][:, :, k] == NodeStatus.ADMISSIBLE, atlas.nodes["spectral_radius"][:, :, k],
                      np.nan)
    mesh = ax.pcolormesh(_edges(atlas.grid.step_lengths), _edges(atlas.grid.periods), np.log10(radius).T, cmap="magma")
    fig.colorbar(mesh, ax=ax, label="log10 spectral radius (open loop)")
    ax.set_xlabel("step length L (m)")
    ax.set_ylabel("period T (s)")
    ax.set_title(f"Open-loop spectral radius, alpha = {math.degrees(atlas.grid.alphas[k]):g} deg, params "
                 f"{atlas.params}", fontsize="medium")
    fig.legend(handles=[Patch(color=NO_GAIT_COLOUR, label="no admissible gait at this alpha (not measured)")],
               fontsize="small", loc="outside lower center")
    return fig


# Reading ---------------------------------------------------------------------------------------

def reading(maps: WalkingMaps) -> list[str]:
    """A short reading of the maps, from their numbers (Markdown bullet lines)."""
    lines = []
    total = maps.region.size
    admissible = int(np.sum(maps.region == 0))
    limits = Counter(CATEGORIES[c] for c in maps.region.ravel() if c != 0)
    limit_text = ", ".join(f"{name} at {n}" for name, n in limits.most_common()) or "none"
    lines.append(f"- **Region.** {admissible} of {total} (L, T) nodes of the atlas (L {maps.step_lengths[0]:g} to "
                 f"{maps.step_lengths[-1]:g} m, T {maps.periods[0]:g} to {maps.periods[-1]:g} s) have an admissible "
                 f"{maps.mode} gait at some alpha in [0, 45] deg"
                 + (f" within the margins ({maps.margins})" if maps.margins else "")
                 + f". Where none is, the limit is: {limit_text} nodes.")
    if maps.boundary:
        periods = np.array([t for _, t in maps.boundary])
        lines.append(f"- **Lowest admissible period** at alpha = {math.degrees(BOUNDARY_ALPHA):g} deg: T_min from "
                     f"{periods.min():.3f} to {periods.max():.3f} s over L = {maps.boundary[0][0]:g} to "
                     f"{maps.boundary[-1][0]:g} m (bisection to 1 ms). Below it the human-like branch goes on, but its "
                     "swing knee bends backwards during the step.")
    if maps.optima:
        alphas = np.degrees([o.alpha for o in maps.optima])
        efforts = np.array([o.W for o in maps.optima])
        best = maps.optima[int(np.argmin(efforts))]
        interior = sum(o.interior for o in maps.optima)
        lines.append(f"- **Optimal arm swing.** alpha* ranges from {alphas.min():.1f} to {alphas.max():.1f} deg over "
                     f"{len(maps.optima)} (L, T) points ({interior} interior minima); W* from {efforts.min():.2f} to "
                     f"{efforts.max():.2f} N m s, least at L = {best.step_length:g} m, T = {best.period:g} s. "
                     + _trend(maps.optima))
        ratios = np.array([o.ratio for o in maps.optima])
        finite = ratios[np.isfinite(ratios)]
        other = GaitMode.ANTI_NORMAL if maps.mode is GaitMode.NORMAL else GaitMode.NORMAL
        if finite.size:
            lines.append(f"- **{other.value.capitalize()} swing** costs {finite.min():.3f} to {finite.max():.3f} times "
                         f"the {maps.mode} gait's W at alpha* ({int(np.sum(finite > 1))} of {finite.size} points above 1"
                         + (f"; {ratios.size - finite.size} {other} gaits not admissible" if finite.size < ratios.size else "")
                         + ").")
    return lines


def _trend(optima: Sequence[Optimum]) -> str:
    """How alpha* moves with L at fixed T and with T at fixed L (least-squares slopes)."""
    lengths = np.array([o.step_length for o in optima])
    periods = np.array([o.period for o in optima])
    alphas = np.degrees([o.alpha for o in optima])
    design = np.column_stack([lengths, periods, np.ones_like(lengths)])
    (d_length, d_period, _), *_ = np.linalg.lstsq(design, alphas, rcond=None)
    return (f"A plane fitted to alpha*(L, T) has slopes {d_length * 0.1:+.2f} deg per 0.1 m of L and "
            f"{d_period * 0.1:+.2f} deg per 0.1 s of T.")
