"""The results page's section on the double support that lasts (docs/model.md section 14), read
from the stored study ``lasting-study.json`` beside the page (``python -m
biped_gait.studies.lasting_study``: many minutes of IPOPT solves, so the page reads it rather than
solving again): E(d) beside W and E(0+), the peak torques and the friction used against d, the
torques at the human-like point d = 0.1 s against the joint table's effort limits, and the arm
amplitude of least E at each d, normal against anti-normal.

The study's file names neither its parameter set nor its joints: its planner is the default
set's (``GaitPlanner()``), so the peak torques are named in that set's actuated order and compared
with its effort limits, and its friction coefficient is the one the friction used is read against.
d in s, E and W in N m s, torques in N m, alpha in degrees (as the file stores them).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from matplotlib.figure import Figure

from ..core.model.biped import BipedModel
from ..core.model.params import DEFAULT_PARAMS, load_params
from .markdown import markdown_table, missing_study, stored_study
from .figures import LINE_STYLES

LASTING_STUDY = "lasting-study.json"  # beside the page
EFFORT_FIGURE = "lasting-effort.png"
ARMS_FIGURE = "lasting-arms.png"
HUMAN_LIKE = 0.1  # s: the human-like double support (at L = T = 0.45 s)
AT_LIMIT = 0.1  # N m: a peak torque this close to its effort limit is at it (IPOPT's bounds hold to ~1e-6)
AT_FRICTION = 1e-3  # the friction used this close to mu is at the floor's limit
MODES = ("normal", "anti-normal")
HEADING = "## A double support that lasts: its effort and the arms' optimum (beyond the paper)"
STUDY_COMMAND = "python -m biped_gait.studies.lasting_study --out docs/lasting-study.json"


@dataclass(frozen=True, eq=False)
class LastingStudy:
    """The stored study: its date and commit, its rows (``durations``: the default gait against d;
    ``alphas``: the arm amplitude's sweep at a few d, both swings; each row as the study wrote it),
    the actuated joints' names and effort limits (N m) and the floor's mu of the set it ran on."""

    date: str
    commit: str
    durations: tuple[dict, ...]
    alphas: tuple[dict, ...]
    joints: tuple[str, ...]
    effort_limits: tuple[float, ...]
    friction: float

    @classmethod
    def load(cls, path: Path, params_name: str = DEFAULT_PARAMS) -> "LastingStudy":
        raw = json.loads(Path(path).read_text())
        return cls(str(raw["date"]), str(raw["commit"]), tuple(raw["durations"]), tuple(raw["alphas"]),
                   *default_joints(params_name))

    def sweep(self, mode: str, duration: float) -> list[dict]:
        """The alpha sweep's rows of one swing at one d, by alpha."""
        return sorted((r for r in self.alphas if r["mode"] == mode and math.isclose(r["d"], duration)),
                      key=lambda r: r["alpha_deg"])

    @property
    def sweep_durations(self) -> list[float]:
        return sorted({r["d"] for r in self.alphas})


@dataclass(frozen=True)
class LastingArmOptimum:
    """The least E of one swing at one d on the study's alpha grid: alpha* (deg), E there, E with
    the arms still (alpha = 0, the same gait in both swings; None if no solve of it finished) and
    whether both neighbours on the grid finished with a larger E (an interior minimum)."""

    mode: str
    duration: float
    alpha_deg: float
    E: float
    still: float | None
    interior: bool

    @property
    def saving(self) -> float | None:
        return None if self.still is None else self.still - self.E


def default_joints(params_name: str = DEFAULT_PARAMS) -> tuple[tuple[str, ...], tuple[float, ...], float]:
    """The actuated joints' names and effort limits (N m) of a parameter set, and its floor's mu."""
    params = load_params(params_name)
    model = BipedModel.from_params(params)
    limits = tuple(float(model.coordinates[k].spec.limits.effort) for k in model.actuated)
    return model.actuated_names, limits, params.friction


def solved(rows: Sequence[dict]) -> list[dict]:
    return [r for r in rows if r["success"]]


def arms_still(study: LastingStudy, duration: float) -> float | None:
    """E at alpha = 0 and ``duration``: the arms still, one gait for both swings (the mean of the
    solves of it that finished: they agree to the solver's tolerance)."""
    values = [r["E"] for mode in MODES for r in solved(study.sweep(mode, duration)) if r["alpha_deg"] == 0.0]
    return sum(values) / len(values) if values else None


def arm_optimum(study: LastingStudy, mode: str, duration: float) -> LastingArmOptimum | None:
    """The least E of ``mode``'s sweep at ``duration``; E at alpha = 0 is the arms still's, from
    either swing (one gait)."""
    still = arms_still(study, duration)
    efforts = [still if r["alpha_deg"] == 0.0 else r["E"] if r["success"] else None for r in study.sweep(mode, duration)]
    alphas = [r["alpha_deg"] for r in study.sweep(mode, duration)]
    known = [k for k, e in enumerate(efforts) if e is not None]
    if not known:
        return None
    k = min(known, key=lambda j: efforts[j])
    neighbours = [efforts[j] for j in (k - 1, k + 1) if 0 <= j < len(efforts)]
    interior = len(neighbours) == 2 and all(e is not None and e > efforts[k] for e in neighbours)
    return LastingArmOptimum(mode, duration, alphas[k], efforts[k], still, interior)


def _grid_minimum(rows: Sequence[dict], key: str) -> dict:
    return min(rows, key=lambda r: r[key])


def _at_limit(study: LastingStudy, peaks: Sequence[float]) -> list[str]:
    return [name for name, peak, limit in zip(study.joints, peaks, study.effort_limits) if peak >= limit - AT_LIMIT]


def _durations_lines(study: LastingStudy) -> list[str]:
    rows = study.durations
    W, E0 = rows[0]["W"], rows[0]["E0"]
    done = solved(rows)
    header = ["d (s)", "E (N m s)", "E / W", "E - E(0+)", "largest peak torque (N m)", "joints at their limit",
              f"friction used (mu = {study.friction:g})", "IPOPT iterations"]
    table = [["0+ (the limit)", f"{E0:.2f}", f"{E0 / W:.2f}", "0", "(impulses only)", "", "", ""]]
    for r in rows:
        if not r["success"]:
            table.append([f"{r['d']:g}", "-", "-", "-", "-", "-", "-", f"{r['iterations']} ({r['message']})"])
            continue
        table.append([f"{r['d']:g}", f"{r['E']:.2f}", f"{r['E'] / W:.2f}", f"{r['E'] - E0:.2f}",
                      f"{max(r['peak_torque']):.1f}", ", ".join(_at_limit(study, r["peak_torque"])) or "none",
                      f"{r['friction_used']:.3f}", str(r["iterations"])])
    efforts = [r["E"] for r in done]
    grows = all(b > a for a, b in zip(efforts, efforts[1:]))
    shares = [100 * (E0 - W) / (r["E"] - W) for r in done]
    limited = [r["d"] for r in done if _at_limit(study, r["peak_torque"])]
    holders = [frozenset(_at_limit(study, r["peak_torque"])) for r in done]
    slope = (done[-1]["E"] - done[0]["E"]) / (done[-1]["d"] - done[0]["d"]) if len(done) > 1 else math.nan
    at_mu = [r["d"] for r in done if r["friction_used"] >= study.friction - AT_FRICTION]
    first = done[0]
    lines = [f"The default gait (L = {first['L']:g} m, T = {first['T']:g} s, alpha = {first['alpha_deg']:g} deg, "
             f"{first['mode']} swing), its paper's W = {W:.2f} N m s (the instantaneous double support) and the limit "
             f"d -> 0+ E(0+) = {E0:.2f} N m s (the held touchdown between the two impulses):", ""]
    lines += markdown_table(header, table)
    lines += ["", f"*Reading.* The double support that lasts costs more than the paper's instantaneous one at every d "
              f"solved (E / W from {efforts[0] / W:.2f} to {efforts[-1] / W:.2f}) and "
              + ("more the longer it lasts" if grows else "not monotonically in d")
              + f", about {slope:.0f} N m s per second of it from d = {done[0]['d']:g} to {done[-1]['d']:g} s. "
              f"E(0+) is already {E0 / W:.2f} W: the held touchdown between the impulses accounts for "
              f"{min(shares):.0f} to {max(shares):.0f} % of E - W over these d, the phase's torques for the rest. "
              f"The study's smallest d is {done[0]['d']:g} s, where E is still {efforts[0] - E0:.2f} N m s above "
              "E(0+); it holds no shorter d, so this page cannot show E(d) reaching E(0+), only E(d) falling "
              f"towards it as d shortens. Nor does it hold the largest d that stays periodic: its largest d, "
              f"{rows[-1]['d']:g} s, " + ("was solved" if rows[-1]["success"] else "was not solved") + ". "
              f"The friction used is at the floor's mu = {study.friction:g} (within {AT_FRICTION:g}) at "
              f"{len(at_mu)} of the {len(done)} d (d = {', '.join(f'{d:g}' for d in at_mu) or 'none'} s), just below "
              "it at the others: the phase uses nearly all the friction there is. Some joint is at the joint "
              f"table's limit (within {AT_LIMIT:g} N m) at {len(limited)} of the {len(done)} d, "
              + ("the same joints at every d." if len(set(holders)) == 1 else
                 "not the same joints at every d: a longer phase does not lower the peak, it moves it between joints.")]
    return lines


def _human_like_lines(study: LastingStudy) -> list[str]:
    rows = [r for r in study.durations if math.isclose(r["d"], HUMAN_LIKE)]
    if not rows or not rows[0]["success"]:
        return [f"The study holds no finished solve at d = {HUMAN_LIKE:g} s."]
    r = rows[0]
    table = [[name, f"{peak:.1f}", f"{limit:g}", f"{100 * peak / limit:.0f} %"]
             for name, peak, limit in zip(study.joints, r["peak_torque"], study.effort_limits)]
    at_limit = _at_limit(study, r["peak_torque"])
    unused = [name for name, peak in zip(study.joints, r["peak_torque"]) if peak < AT_LIMIT]
    lines = [f"The human-like point, d = {HUMAN_LIKE:g} s at L = {r['L']:g} m, T = {r['T']:g} s (alpha = "
             f"{r['alpha_deg']:g} deg, {r['mode']}): E = {r['E']:.2f} N m s, the peak |Gamma_j| over the phase per joint "
             "against the joint table's effort limit. The study stores each joint's peak only, not the torques' "
             "time history; the joints are named in the default set's actuated order (the file does not name them):",
             ""]
    lines += markdown_table(["joint", "peak torque (N m)", "effort limit (N m)", "of the limit"], table)
    lines += ["", f"*Reading.* {len(at_limit)} of {len(study.joints)} joints reach their limit "
              f"({', '.join(at_limit) or 'none'}): the least-effort phase rides its torque bounds. "
              + (f"{', '.join(unused)} {'is' if len(unused) == 1 else 'are'} not used (peak below {AT_LIMIT:g} N m). "
                 if unused else "")
              + f"The friction used is {r['friction_used']:.3f} of mu = {study.friction:g}."]
    return lines


def _arms_lines(study: LastingStudy) -> list[str]:
    durations = study.sweep_durations
    alphas = sorted({r["alpha_deg"] for r in study.alphas})
    grid = []
    for mode in MODES:
        for d in durations:
            best = arm_optimum(study, mode, d)
            cells = [("-" if not r["success"] else f"**{r['E']:.2f}**" if best and r["alpha_deg"] == best.alpha_deg
                      else f"{r['E']:.2f}") for r in study.sweep(mode, d)]
            grid.append([f"{mode}, {d:g} s", *cells])
    first = study.sweep(MODES[0], durations[0])
    impulsive = [["E(0+), the limit d -> 0+", *(f"{r['E0']:.2f}" for r in first)],
                 ["W, the paper's (d = 0)", *(f"{r['W']:.2f}" for r in first)]]
    optima = [arm_optimum(study, mode, d) for d in durations for mode in MODES]
    table = []
    for o in optima:
        if o is None:
            continue
        saving = "-" if o.saving is None else f"{o.saving:.2f} ({100 * o.saving / o.still:.0f} %)"
        table.append([f"{o.duration:g}", o.mode, f"{o.alpha_deg:g}", f"{o.E:.2f}",
                      "-" if o.still is None else f"{o.still:.2f}", saving,
                      "interior" if o.interior else "at an end of the grid, or beside a failed solve"])
    e0_best, w_best = _grid_minimum(first, "E0"), _grid_minimum(first, "W")
    step = alphas[1] - alphas[0] if len(alphas) > 1 else math.nan
    normal = {d: arm_optimum(study, "normal", d) for d in durations}
    both, cheaper, equal = 0, 0, 0
    for d in durations:
        anti = {r["alpha_deg"]: r for r in solved(study.sweep("anti-normal", d))}
        for r in solved(study.sweep("normal", d)):
            other = anti.get(r["alpha_deg"])
            if other is None:
                continue
            both += 1
            if r["alpha_deg"] == 0.0:
                equal += 1
            elif r["E"] < other["E"]:
                cheaper += 1
    failed = len(study.alphas) - len(solved(study.alphas))
    normal_alphas = ", ".join(f"{normal[d].alpha_deg:g}" for d in durations if normal[d] is not None)
    grows = [normal[d].alpha_deg for d in durations if normal[d] is not None]
    one_only = [d for d in durations
                if len({m for m in MODES for r in solved(study.sweep(m, d)) if r["alpha_deg"] == 0.0}) == 1]
    survives = all(o is not None and o.interior and o.alpha_deg > 0 for o in normal.values()) and cheaper == both - equal
    towards = survives and all(b > a for a, b in zip(grows, grows[1:])) and grows[-1] <= w_best["alpha_deg"]
    lines = [f"The paper's main result under a lasting double support: E against the arm amplitude alpha at L = "
             f"{first[0]['L']:g} m, T = {first[0]['T']:g} s for d = {', '.join(f'{d:g}' for d in durations)} s, both "
             f"swings, every {step:g} deg (N m s; bold: the least E of the row; a dash: the solve did not finish, "
             f"{failed} of {len(study.alphas)}, IPOPT stopping at its iteration limit). The impulsive rows are the "
             "same gaits' E(0+) and W (normal swing):", ""]
    lines += markdown_table(["swing, d", *(f"{a:g}" for a in alphas)], grid + impulsive)
    lines += ["", f"The optimal amplitude alpha* on this {step:g} deg grid, its E, and the saving against the arms "
              "still (alpha = 0, one gait for both swings):", ""]
    lines += markdown_table(["d (s)", "swing", "alpha* (deg)", "E at alpha*", "E, arms still", "saving (N m s)", "minimum"],
                    table)
    lines += ["", f"*Reading.* The normal swing's alpha* is {normal_alphas} deg at d = "
              f"{', '.join(f'{d:g}' for d in durations)} s ("
              + ("growing with d" if all(b > a for a, b in zip(grows, grows[1:])) else "not growing with d")
              + f"; on a {step:g} deg grid, so each within {step / 2:g} deg). "
              f"The normal swing is cheaper than the anti-normal one at {cheaper} of the {both - equal} amplitudes "
              f"above 0 where both finished (at alpha = 0 the two are the same gait). In the impulsive limit "
              + ("the arms' optimum leaves: " if e0_best["alpha_deg"] == 0.0 else "")
              + f"E(0+) is least at alpha = {e0_best['alpha_deg']:g} deg on the grid, where the "
              f"paper's W is least at {w_best['alpha_deg']:g} deg. "
              + ("So the arms' optimum survives a double support that lasts (an interior minimum of the normal swing "
                 "at every d, cheaper than the anti-normal swing)"
                 + (", and comes back towards the paper's as the phase lengthens. " if towards else ". ")
                 if survives else "So on these numbers the arms' optimum does not clearly survive a double support "
                 "that lasts. ")
              + "A dash is the solver's failure, not a proof that no gait exists"
              + (f": at alpha = 0 the two swings are the same gait, yet at d = {', '.join(f'{d:g}' for d in one_only)} s "
                 "one solve of it finished and the other did not." if one_only else ".")]
    return lines


def lasting_lines(study: LastingStudy | None, path: Path) -> list[str]:
    """The section's text, below its heading; ``study`` None: none was found at ``path``."""
    if study is None:
        return missing_study(path, STUDY_COMMAND, "many minutes of IPOPT solves")
    lines = [f"The cycle of docs/model.md section 14: the ballistic single support, the paper's I^-, a held "
             "touchdown, d seconds of double support with finite torques (the closed chain, both reactions in "
             "their friction pyramids, each torque within the joint table's effort), the paper's I^+. "
             "E = Sum |I^-| + integral of Sum |Gamma_j| dt + Sum |I^+|. "
             + stored_study(LASTING_STUDY, STUDY_COMMAND, study.date, study.commit, ", every solve cold"), "", "### Effort, torques and friction against d", ""]
    lines += _durations_lines(study)
    lines += ["", f"![E against d, with E(0+) and W]({EFFORT_FIGURE})", "", "### The human-like point", ""]
    lines += _human_like_lines(study)
    lines += ["", "### The optimal arm swing against d", ""]
    lines += _arms_lines(study)
    lines += ["", f"![E against alpha at each d, normal solid, anti-normal dashed]({ARMS_FIGURE})", ""]
    return lines


def _axes() -> tuple[Figure, object]:
    fig = Figure(figsize=(9.0, 5.0), layout="constrained")
    return fig, fig.add_subplot()


def effort_figure(study: LastingStudy) -> Figure:
    """E(d) of the default gait, E(0+) at d = 0 and as a line, W as a line."""
    fig, ax = _axes()
    done = solved(study.durations)
    W, E0 = study.durations[0]["W"], study.durations[0]["E0"]
    ax.plot([r["d"] for r in done], [r["E"] for r in done], "o-", color="C0", label="E(d), the lasting double support")
    ax.plot([0.0], [E0], "s", color="C1")
    ax.axhline(E0, color="C1", ls="--", label=f"E(0+) = {E0:.2f}, the limit d -> 0+")
    ax.axhline(W, color="C2", ls=":", label=f"W = {W:.2f}, the paper's instantaneous double support")
    ax.set_xlim(left=-0.01)
    ax.set_ylim(0.0, 1.1 * max(r["E"] for r in done))
    ax.set_xlabel("duration of the double support d (s)")
    ax.set_ylabel("effort (N m s)")
    r = study.durations[0]
    ax.set_title(f"Effort against d: L = {r['L']:g} m, T = {r['T']:g} s, alpha = {r['alpha_deg']:g} deg, {r['mode']} "
                 f"(study of {study.date}, {study.commit})")
    ax.legend(loc="lower right")
    return fig


def arms_figure(study: LastingStudy) -> Figure:
    """E against alpha at each d of the sweep, both swings (a failed solve a gap), with the
    same gaits' E(0+) and W."""
    fig, ax = _axes()
    for k, d in enumerate(study.sweep_durations):
        for mode in MODES:
            rows = study.sweep(mode, d)  # a failed solve breaks the curve
            ax.plot([r["alpha_deg"] for r in rows], [r["E"] if r["success"] else math.nan for r in rows],
                    LINE_STYLES[mode], marker="o",
                    color=f"C{k}", label=f"d = {d:g} s, {mode}")
            best = arm_optimum(study, mode, d)
            ax.plot([best.alpha_deg], [best.E], "*", color=f"C{k}", markersize=14)
    first = study.sweep(MODES[0], study.sweep_durations[0])
    ax.plot([r["alpha_deg"] for r in first], [r["E0"] for r in first], "-", marker="s", color="0.5",
            label="E(0+), normal")
    ax.plot([r["alpha_deg"] for r in first], [r["W"] for r in first], ":", marker="s", color="0.3",
            label="W (d = 0), normal")
    ax.set_xlabel("arm amplitude alpha (deg)")
    ax.set_ylabel("effort (N m s)")
    ax.set_title(f"Effort against the arm amplitude (stars: least E of each curve; study of {study.date}, "
                 f"{study.commit})")
    ax.legend(loc="upper left", ncols=3, fontsize="small")
    return fig


def lasting_figures(study: LastingStudy | None) -> dict[str, tuple]:
    """Caption -> (figure, file name); none without a study."""
    if study is None:
        return {}
    return {"The lasting double support: E against d": (effort_figure(study), EFFORT_FIGURE),
            "The lasting double support: E against alpha at each d": (arms_figure(study), ARMS_FIGURE)}
