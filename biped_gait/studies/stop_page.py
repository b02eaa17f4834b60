"""The results page's section on the stop (docs/model.md sections 14 and 14.2): the default gait
brought to rest in one double support of 2 s, read from the plan the package keeps
(``core/gait/spline_support.kept_stop_path``; ``studies/spline_study.py`` makes it): its duration,
effort, peak torques and friction used, and a picture of it. Nothing is solved.

``python -m biped_gait.studies.stop_page`` rewrites the section (and its figure) of an existing page
alone, as ``actuated_page`` does its own.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from ..core.gait.lasting_support import LastingSupport
from ..core.gait.spline_support import kept_stop_path, load_plan
from ..core.model.biped import BipedModel
from ..core.model.params import load_params
from .actuated_page import HEADING as ACTUATED_HEADING
from .figures import save
from .markdown import markdown_table, page_argument, splice_section

HEADING = "## The stop: from the gait to standing (beyond the paper)"
STOP_FIGURE = "stop.png"
STUDY_COMMAND = "python -m biped_gait.studies.spline_study"


def kept_stop_plan() -> tuple[BipedModel, LastingSupport, dict]:
    """The default parameter set's model and the package's kept stop, with its ``meta``."""
    model = BipedModel.from_params(load_params(None))
    support, meta = load_plan(kept_stop_path(), model)
    return model, support, meta


def stop_lines(model: BipedModel, support: LastingSupport, meta: dict) -> list[str]:
    """The section's text (under ``HEADING``): what the kept stop is and its figures."""
    impulses = float(np.abs(support.i_minus).sum())
    forces = support.contact_forces[..., 2]
    lines = [f"The default gait (L = {meta['L']:g} m, T = {meta['T']:g} s, alpha = {math.degrees(meta['alpha']):.1f} "
             f"deg, {meta['mode']}) brought to rest in one double support: I^- and the held touchdown, then "
             f"{support.duration:g} s with both feet down and finite torques, ending at rest in the standing posture "
             "(docs/model.md section 14); the simulator walks it on `/cmd_vel` 0 and then stands (section 14.2). From "
             f"the plan the package keeps (`biped_gait/core/data/stop/{kept_stop_path().name}`, `{STUDY_COMMAND}`), "
             f"solved on {meta['date']} at commit {meta['commit']}; the page reads it and solves nothing. The floor's "
             f"mu = {model.params.friction:g}; the plan keeps both feet pressing by at least "
             f"{meta['least_normal_force']:g} N within mu = {meta['friction']:g}.", ""]
    lines += markdown_table(
        ["duration (s)", "E (N m s)", "sum abs(I^-) (N m s)", "torques' integral (N m s)", "peak torque (N m)",
         "friction used", "least normal force (N)"],
        [[f"{support.duration:g}", f"{support.effort_total:.2f}", f"{impulses:.2f}", f"{support.effort_l1:.2f}",
          f"{support.peak_torque.max():.1f}", f"{support.friction_used:.3f}", f"{forces.min():.1f}"]])
    lines += ["", "Each joint's I^- and peak torque:", ""]
    lines += markdown_table(["joint", "I^- (N m s)", "peak torque (N m)"],
                            [[name, f"{i:.2f}", f"{peak:.1f}"]
                             for name, i, peak in zip(model.actuated_names, support.i_minus, support.peak_torque)])
    lines += ["", f"![The stop: joint angles, torques and the feet's reactions over its {support.duration:g} s]"
              f"({STOP_FIGURE})"]
    return lines


def stop_figure(model: BipedModel, support: LastingSupport, meta: dict) -> Figure:
    """The stop's joint angles, torques, and both feet's normal forces and friction ratios against t."""
    fig = Figure(figsize=(11.0, 8.0), layout="constrained")
    angles, torques, forces, ratios = fig.subplots(2, 2).ravel()
    at = np.asarray(model.ds_of_single)
    for k, name in enumerate(model.names):
        angles.plot(support.t, support.x[:, at[k]], label=name)
    angles.set_ylabel("joint angle (rad)")
    angles.legend(fontsize="x-small", ncol=2)
    for k, name in enumerate(model.actuated_names):
        torques.plot(support.t, support.torques[:, k], label=name)
    torques.set_ylabel("joint torque (N m)")
    torques.legend(fontsize="x-small", ncol=2)
    for k, foot in enumerate(("old stance foot", "new stance foot")):
        f = support.contact_forces[:, k]
        forces.plot(support.t, f[:, 2], label=foot)
        ratios.plot(support.t, np.hypot(f[:, 0], f[:, 1]) / f[:, 2], label=foot)
    ratios.axhline(model.params.friction, color="k", ls=":", label="the floor's mu")
    forces.set_ylabel("normal force (N)")
    ratios.set_ylabel("friction used |F_xy| / F_z")
    for ax in (angles, torques, forces, ratios):
        ax.set_xlabel("time in the stop (s)")
    forces.legend(fontsize="small")
    ratios.legend(fontsize="small")
    fig.suptitle(f"The stop of the default gait (plan of {meta['date']}, {meta['commit']}): E = "
                 f"{support.effort_total:.1f} N m s")
    return fig


def splice(page: str, lines: list[str]) -> str:
    """``page`` with its stop section replaced by ``lines``; a page without one gets it after the
    actuated swing's section (``markdown.splice_section``)."""
    return splice_section(page, HEADING, lines, ACTUATED_HEADING)


def main(argv: list[str] | None = None) -> int:
    page = page_argument(argv, "stop", "the kept plan")
    plan = kept_stop_plan()
    page.write_text(splice(page.read_text(), stop_lines(*plan)))
    save(stop_figure(*plan), page.parent / STOP_FIGURE)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
