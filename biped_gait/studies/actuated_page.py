"""The results page's section on the actuated swing (docs/model.md section 15), read from the
stored study ``actuated-swing-study.json`` beside the page (``python -m
biped_gait.studies.actuated_swing_study``: an hour of IPOPT solves, so the page reads it): E and
the peak torque per joint against the swing's actuated time tau and the double support's d, the
smallest tau solved within the joint table's limits, and the arm amplitude of least E, normal
against anti-normal. ``python -m biped_gait.studies.actuated_page`` rewrites that section of
docs/results.md from the file alone, without recomputing the rest of the page.

The file names neither its parameter set nor its joints: its planner is the default set's, so the
peaks are named in that set's actuated order and compared with its effort limits (as for the
lasting study). tau and d in s, E and W in N m s, torques in N m, alpha in degrees.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from matplotlib.figure import Figure

from .figures import save
from .lasting_page import AT_LIMIT, HEADING as LASTING_HEADING, MODES, default_joints, solved
from .markdown import markdown_table, missing_study, page_argument, splice_section, stored_study

ACTUATED_STUDY = "actuated-swing-study.json"  # beside the page
ACTUATED_FIGURE = "actuated-effort.png"
HEADING = "## The actuated swing: torques within the motors' limits (beyond the paper)"
STUDY_COMMAND = "python -m biped_gait.studies.actuated_swing_study --out docs/actuated-swing-study.json"


@dataclass(frozen=True, eq=False)
class ActuatedStudy:
    """The stored study: its date and commit, its rows as the study wrote them (``taus``: the
    default gait against tau at each d, within the limits; ``free_taus``: the limits lifted;
    ``alphas``: the arm amplitude's sweep at a few tau, both swings), and the default set's actuated
    joints' names and effort limits (N m)."""

    date: str
    commit: str
    taus: tuple[dict, ...]
    free_taus: tuple[dict, ...]
    alphas: tuple[dict, ...]
    joints: tuple[str, ...]
    effort_limits: tuple[float, ...]

    @classmethod
    def load(cls, path: Path) -> "ActuatedStudy":
        raw = json.loads(Path(path).read_text())
        joints, limits, _ = default_joints()
        return cls(str(raw["date"]), str(raw["commit"]), tuple(raw["taus"]), tuple(raw["free_taus"]),
                   tuple(raw["alphas"]), joints, limits)

    @property
    def durations(self) -> list[float]:
        return sorted({r["d"] for r in self.taus})

    def against_tau(self, duration: float) -> list[dict]:
        """The within-limits rows at one d, from the longest tau."""
        return sorted((r for r in self.taus if math.isclose(r["d"], duration)), key=lambda r: -r["tau"])

    def sweep(self, mode: str, tau: float) -> list[dict]:
        return sorted((r for r in self.alphas if r["mode"] == mode and math.isclose(r["tau"], tau)),
                      key=lambda r: r["alpha_deg"])

    @property
    def sweep_taus(self) -> list[float]:
        return sorted({r["tau"] for r in self.alphas}, reverse=True)


def smallest_tau(study: ActuatedStudy, duration: float) -> tuple[float | None, float | None]:
    """(the smallest tau solved, the largest tau refused below it) at ``duration``."""
    rows = study.against_tau(duration)
    done = [r["tau"] for r in solved(rows)]
    least = min(done) if done else None
    refused = [r["tau"] for r in rows if not r["success"] and (least is None or r["tau"] < least)]
    return least, (max(refused) if refused else None)


def tau_optimum(study: ActuatedStudy, mode: str, tau: float) -> dict | None:
    """The least-E finished row of ``mode``'s sweep at ``tau``."""
    done = solved(study.sweep(mode, tau))
    return min(done, key=lambda r: r["E"]) if done else None


def _at_limit(study: ActuatedStudy, peaks) -> int:
    return sum(peak >= limit - AT_LIMIT for peak, limit in zip(peaks, study.effort_limits))


def _taus_lines(study: ActuatedStudy) -> list[str]:
    header = ["d (s)", "tau (s)", "E (N m s)", "E impulsive (N m s)",
              *(f"{n} (limit {lim:g})" for n, lim in zip(study.joints, study.effort_limits)), "IPOPT iterations"]
    table = []
    for d in study.durations:
        for r in study.against_tau(d):
            if r["success"]:
                table.append([f"{d:g}", f"{r['tau']:g}", f"{r['E']:.2f}", f"{r['E_impulsive']:.2f}",
                              *(f"{p:.1f}" for p in r["peak_torque"]), str(r["iterations"])])
            else:
                table.append([f"{d:g}", f"{r['tau']:g}", "-", f"{r['E_impulsive']:.2f}",
                              *("-" for _ in study.joints), f"{r['iterations']} (no cycle)"])
    first = study.taus[0]
    lines = [f"The default gait (L = {first['L']:g} m, T = {first['T']:g} s, alpha = {first['alpha_deg']:g} deg, "
             f"{first['mode']} swing), the paper's W = {first['W']:.2f} N m s. Peak |Gamma_j| per joint over the "
             "cycle (N m; the file stores peaks only), every torque within the joint table's effort limit; "
             "E impulsive is the same gait's E with the swing ballistic (section 14). A dash: IPOPT stopped at its "
             "iteration limit without a cycle:", ""]
    lines += markdown_table(header, table)
    reading = []
    for d in study.durations:
        done = solved(study.against_tau(d))
        least, refused = smallest_tau(study, d)
        at = [_at_limit(study, r["peak_torque"]) for r in done]
        reading.append(f"at d = {d:g} s E grows from {done[0]['E']:.2f} (tau = {done[0]['tau']:g} s) to "
                       f"{done[-1]['E']:.2f} (tau = {least:g} s), {min(at)} to {max(at)} of the "
                       f"{len(study.joints)} joints at their limit (within {AT_LIMIT:g} N m); the smallest tau solved is "
                       f"{least:g} s, none below it from {refused:g} s down")
    dones = [solved(study.against_tau(d)) for d in study.durations]
    least = {d: smallest_tau(study, d)[0] for d in study.durations}
    elsewhere = [f"tau = {r['tau']:g} s, d = {r['d']:g} s, alpha = {r['alpha_deg']:g} deg ({r['mode']})"
                 for r in solved(study.alphas) if any(math.isclose(r["d"], d) and r["tau"] < t for d, t in least.items())]
    grows = all(b["E"] > a["E"] for done in dones for a, b in zip(done, done[1:]))
    above = all(r["E"] > r["E_impulsive"] for done in dones for r in done)
    lines += ["", "*Reading.* " + ("A shorter actuated swing costs more: " if grows else "E is not monotonic in tau: ")
              + "; ".join(reading) + ". "
              + ("Every E here is above the impulsive E of the same gait: with the torques bounded, the cycle costs "
                 "more than its impulses. " if above else "Some E here is at or below the impulsive E of the same gait. ")
              + "The refusals are the solver's verdict (IPOPT at its iteration limit, each started from the last tau "
              "solved), not a proof that no cycle within the limits exists at that tau"
              + (": the arm sweep below found cycles within the limits at " + ", ".join(elsewhere) + "."
                 if elsewhere else ".")]
    return lines


def _free_lines(study: ActuatedStudy) -> list[str]:
    table = [[f"{r['tau']:g}", f"{r['E']:.2f}" if r["success"] else "-", f"{r['E_impulsive']:.2f}",
              f"{max(r['peak_torque']):.0f}" if r["success"] else "-",
              str(r["iterations"]) + ("" if r["success"] else " (no cycle)")] for r in study.free_taus]
    done = solved(study.free_taus)
    lines = ["The limits lifted (d = 0): tau -> 0 should bring E to the impulsive E, with torques growing as 1/tau:", ""]
    lines += markdown_table(["tau (s)", "E (N m s)", "E impulsive", "largest peak torque (N m)", "IPOPT iterations"],
                            table)
    lines += ["", f"*Reading.* Without limits the solver finishes down to tau = {min(r['tau'] for r in done):g} s only, "
              f"with peaks up to {max(max(r['peak_torque']) for r in done):.0f} N m, far beyond any motor; E is "
              + ", ".join(f"{r['E']:.2f} at {r['tau']:g} s" for r in done)
              + " (the impulsive E is " + f"{done[0]['E_impulsive']:.2f}): the study does not show the limit tau -> 0 "
              "reached, and below that tau the solver found no cycle."]
    return lines


def _arms_lines(study: ActuatedStudy) -> list[str]:
    alphas = sorted({r["alpha_deg"] for r in study.alphas})
    grid = []
    for mode in MODES:
        for tau in study.sweep_taus:
            best = tau_optimum(study, mode, tau)
            grid.append([f"{mode}, {tau:g} s", *("-" if not r["success"] else f"**{r['E']:.2f}**" if r is best
                                                 else f"{r['E']:.2f}" for r in study.sweep(mode, tau))])
    table, survives = [], []
    for tau in study.sweep_taus:
        for mode in MODES:
            best = tau_optimum(study, mode, tau)
            still = [r for r in solved(study.sweep(mode, tau)) if r["alpha_deg"] == 0.0]
            if best is None:
                table.append([f"{tau:g}", mode, "-", "-", "-", "no solve finished"])
                continue
            saving = f"{still[0]['E'] - best['E']:.2f}" if still else "- (alpha = 0 not solved)"
            table.append([f"{tau:g}", mode, f"{best['alpha_deg']:g}", f"{best['E']:.2f}",
                          f"{still[0]['E']:.2f}" if still else "-", saving])
            if mode == "normal":
                survives.append((tau, best["alpha_deg"], still[0]["E"] - best["E"] if still else None))
    d = study.alphas[0]["d"]
    step = alphas[1] - alphas[0]
    lines = [f"The arms' optimum with the swing actuated: E against alpha at d = {d:g} s for tau = "
             f"{', '.join(f'{t:g}' for t in study.sweep_taus)} s, both swings, every {step:g} deg (N m s; bold: least "
             "E of the row; a dash: no cycle, IPOPT at its iteration limit):", ""]
    lines += markdown_table(["swing, tau", *(f"{a:g}" for a in alphas)], grid)
    lines += ["", "alpha* on this grid, its E, and the saving against the arms still (alpha = 0):", ""]
    lines += markdown_table(["tau (s)", "swing", "alpha* (deg)", "E at alpha*", "E, arms still", "saving (N m s)"], table)
    parts = [f"at tau = {t:g} s alpha* = {a:g} deg saving {s:.2f} N m s" if s is not None else
             f"at tau = {t:g} s alpha* = {a:g} deg (alpha = 0 not solved)" for t, a, s in survives]
    anti = [o for o in (tau_optimum(study, "anti-normal", t) for t in study.sweep_taus) if o is not None]
    both = cheaper = 0
    for tau in study.sweep_taus:
        others = {r["alpha_deg"]: r for r in solved(study.sweep("anti-normal", tau))}
        for r in solved(study.sweep("normal", tau)):
            if r["alpha_deg"] > 0.0 and r["alpha_deg"] in others:
                both += 1
                cheaper += r["E"] < others[r["alpha_deg"]]["E"]
    percents = [100 * s / tau_optimum(study, "normal", t)["E"] for t, _, s in survives if s is not None]
    partial = [f"{t:g}" for t in study.sweep_taus if not all(r["success"] for r in study.sweep("normal", t))]
    lines += ["", "*Reading.* Does the arms' optimum survive when no torque exceeds a motor's limit? The normal swing's "
              + "; ".join(parts) + f" (each within {step / 2:g} deg on this grid); where alpha = 0 was solved the saving "
              f"is at most {max(percents):.1f} % of E, where the default gait swings its arms by "
              f"{study.taus[0]['alpha_deg']:g} deg (the paper's optimum of the impulsive gait). "
              + ("So a small arm swing still pays, by little. " if all(p > 0 for p in percents)
                 else "So the arms' optimum does not survive: the arms still cost least. ")
              + "The anti-normal "
              "swing's least E is at " + ", ".join(f"{o['alpha_deg']:g} deg" for o in anti)
              + " (tau = " + ", ".join(f"{o['tau']:g}" for o in anti) + f" s). Where both finished at an alpha above 0 the "
              f"normal swing is the cheaper at {cheaper} of {both}. "
              + (f"At tau = {', '.join(partial)} s some solves did not finish, so that row's alpha* is the least of "
                 "those that did, not a bracketed minimum." if partial else "")]
    return lines


def actuated_lines(study: ActuatedStudy | None, path: Path) -> list[str]:
    """The section's text, below its heading; ``study`` None: none was found at ``path``."""
    if study is None:
        return missing_study(path, STUDY_COMMAND, "about an hour of IPOPT solves")
    lines = ["The cycle of docs/model.md section 15: the swing leg is actuated for tau seconds after the double "
             "support and tau seconds before the next one, every torque within the joint table's effort limit, the "
             "rest of the single support ballistic. "
             + stored_study(ACTUATED_STUDY, STUDY_COMMAND, study.date, study.commit),
             "", "### Effort and peak torques against tau and d", ""]
    lines += _taus_lines(study)
    lines += ["", "![E against tau at each d (dotted: the impulsive E); E against alpha at each tau, normal solid, "
              f"anti-normal dashed]({ACTUATED_FIGURE})", "", "### The limits lifted", ""]
    lines += _free_lines(study)
    lines += ["", "### The optimal arm swing with the swing actuated", ""]
    lines += _arms_lines(study)
    return lines


def actuated_figure(study: ActuatedStudy) -> Figure:
    """E against tau at each d (within the limits), and E against alpha at each tau, both swings."""
    fig = Figure(figsize=(11.0, 4.5), layout="constrained")
    left, right = fig.subplots(1, 2)
    for k, d in enumerate(study.durations):
        done = solved(study.against_tau(d))
        left.plot([r["tau"] for r in done], [r["E"] for r in done], "o-", color=f"C{k}", label=f"E, d = {d:g} s")
        left.axhline(done[0]["E_impulsive"], color=f"C{k}", ls=":", label=f"E impulsive, d = {d:g} s")
    left.set_xlabel("actuated swing time tau (s)")
    left.set_ylabel("effort (N m s)")
    left.legend(fontsize="small")
    for k, tau in enumerate(study.sweep_taus):
        for mode, style in zip(MODES, ("-", "--")):
            rows = study.sweep(mode, tau)
            right.plot([r["alpha_deg"] for r in rows], [r["E"] if r["success"] else math.nan for r in rows], style,
                       marker="o", color=f"C{k}", label=f"tau = {tau:g} s, {mode}")
    right.set_xlabel("arm amplitude alpha (deg)")
    right.set_ylabel("effort (N m s)")
    right.legend(fontsize="small")
    fig.suptitle(f"The actuated swing (study of {study.date}, {study.commit})")
    return fig


def splice(page: str, lines: list[str]) -> str:
    """``page`` with its actuated-swing section replaced by ``lines``; a page without one gets it
    after the lasting double support's section (``markdown.splice_section``)."""
    return splice_section(page, HEADING, lines, LASTING_HEADING)


def main(argv: list[str] | None = None) -> int:
    page = page_argument(argv, "actuated-swing", "its stored study")
    path = page.parent / ACTUATED_STUDY
    study = ActuatedStudy.load(path) if path.is_file() else None
    page.write_text(splice(page.read_text(), actuated_lines(study, path)))
    if study is not None:
        save(actuated_figure(study), page.parent / ACTUATED_FIGURE)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
