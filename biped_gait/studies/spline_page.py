"""The results page's sections on the stop and the start (docs/model.md sections 14, 14.2 and 14.3):
the default gait brought to rest in one double support of 2 s, and set off from rest onto it in
another, each read from the plan the package keeps (``core/gait/spline_support.kept_path``;
``studies/spline_study.py`` makes them): its duration, effort, peak torques and friction used, and a
picture of it. Nothing is solved. A kind of phase the package keeps no plan of has no section.

``python -m biped_gait.studies.spline_page`` rewrites the sections (and their figures) of an existing
page alone, as ``actuated_page`` does its own.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from ..core.gait.lasting_support import LastingSupport
from ..core.gait.spline_support import KINDS, kept_path, load_plan
from ..core.model.biped import BipedModel
from ..core.model.params import load_params
from .actuated_page import HEADING as ACTUATED_HEADING
from .figures import save
from .markdown import markdown_table, page_argument, splice_section

HEADINGS = {"stop": "## The stop: from the gait to standing (beyond the paper)",
            "start": "## The start: from standing onto the gait (beyond the paper)"}
FIGURES = {kind: f"{kind}.png" for kind in KINDS}
STUDY_COMMAND = "python -m biped_gait.studies.spline_study"
# What each is, in the page's words: the phase, its impulse, where the simulator walks it.
WHAT = {"stop": ("brought to rest in one double support: I^- and the held touchdown, then {d:g} s with both feet "
                 "down and finite torques, ending at rest in the standing posture (docs/model.md section 14); the "
                 "simulator walks it on `/cmd_vel` 0 and then stands (section 14.2)", "I^-"),
        "start": ("set off from rest in one double support: {d:g} s with both feet down and finite torques from rest "
                  "in the standing posture to the gait's touchdown posture, then I^+ onto the gait's next step "
                  "(docs/model.md section 14.3)", "I^+")}


def kept_plans() -> dict[str, tuple[BipedModel, LastingSupport, dict]]:
    """The default parameter set's model with each plan the package keeps (by kind), and its ``meta``."""
    model = BipedModel.from_params(load_params(None))
    return {kind: (model, *load_plan(kept_path(kind), model)) for kind in KINDS if kept_path(kind).is_file()}


def impulse(kind: str, support: LastingSupport) -> np.ndarray:
    """The phase's impulse (N m s): the stop's I^-, the start's I^+."""
    return support.i_minus if kind == "stop" else support.i_plus


def section_lines(kind: str, model: BipedModel, support: LastingSupport, meta: dict) -> list[str]:
    """The section's text (under ``HEADINGS[kind]``): what the kept plan is and its figures."""
    what, name = WHAT[kind]
    impulses = impulse(kind, support)
    forces = support.contact_forces[..., 2]
    lines = [f"The default gait (L = {meta['L']:g} m, T = {meta['T']:g} s, alpha = {math.degrees(meta['alpha']):.1f} "
             f"deg, {meta['mode']}) {what.format(d=support.duration)}. From the plan the package keeps "
             f"(`biped_gait/core/data/{kind}/{kept_path(kind).name}`, `{STUDY_COMMAND}`), solved on {meta['date']} "
             f"at commit {meta['commit']}; the page reads it and solves nothing. The floor's mu = "
             f"{model.params.friction:g}; the plan keeps both feet pressing by at least "
             f"{meta['least_normal_force']:g} N within mu = {meta['friction']:g}.", ""]
    lines += markdown_table(
        ["duration (s)", "E (N m s)", f"sum abs({name}) (N m s)", "torques' integral (N m s)", "peak torque (N m)",
         "friction used", "least normal force (N)"],
        [[f"{support.duration:g}", f"{support.effort_total:.2f}", f"{np.abs(impulses).sum():.2f}",
          f"{support.effort_l1:.2f}", f"{support.peak_torque.max():.1f}", f"{support.friction_used:.3f}",
          f"{forces.min():.1f}"]])
    lines += ["", f"Each joint's {name} and peak torque:", ""]
    lines += markdown_table(["joint", f"{name} (N m s)", "peak torque (N m)"],
                            [[joint, f"{i:.2f}", f"{peak:.1f}"]
                             for joint, i, peak in zip(model.actuated_names, impulses, support.peak_torque)])
    lines += ["", f"![The {kind}: joint angles, torques and the feet's reactions over its {support.duration:g} s]"
              f"({FIGURES[kind]})"]
    return lines


def section_figure(kind: str, model: BipedModel, support: LastingSupport, meta: dict) -> Figure:
    """The phase's joint angles, torques, and both feet's normal forces and friction ratios against t."""
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
        ax.set_xlabel(f"time in the {kind} (s)")
    forces.legend(fontsize="small")
    ratios.legend(fontsize="small")
    fig.suptitle(f"The {kind} of the default gait (plan of {meta['date']}, {meta['commit']}): E = "
                 f"{support.effort_total:.1f} N m s")
    return fig


def splice(page: str, kind: str, lines: list[str]) -> str:
    """``page`` with its section on ``kind`` replaced by ``lines``; a page without one gets it after
    the section before it (the actuated swing's for the stop, the stop's for the start:
    ``markdown.splice_section``)."""
    return splice_section(page, HEADINGS[kind], lines, ACTUATED_HEADING if kind == "stop" else HEADINGS["stop"])


def main(argv: list[str] | None = None) -> int:
    page = page_argument(argv, "stop and start", "the kept plans")
    text = page.read_text()
    for kind, plan in kept_plans().items():
        text = splice(text, kind, section_lines(kind, *plan))
        save(section_figure(kind, *plan), page.parent / FIGURES[kind])
    page.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
