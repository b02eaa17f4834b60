"""The references generated from the code, so that they cannot drift from it: ``docs/cli.md``
from the parsers of the command-line entry points (with the verb x gait-option table), and the
parameter tables of ``docs/ros.md`` from the nodes' parameter tables (between its
``<!-- parameters NODE -->`` and ``<!-- end parameters -->`` marks).

``python -m biped_gait.reference_docs`` rewrites both; ``tests/test_reference_docs.py`` checks
that they are current (run the command after changing an option or a parameter).
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from pathlib import Path

from .cli_parser import GAIT_VERBS, build_parser
from .gait_options import OPTIONS

DOCS = Path(__file__).resolve().parents[1] / "docs"
CLI_PAGE = DOCS / "cli.md"
ROS_PAGE = DOCS / "ros.md"
USAGE_WIDTH = 100  # columns of the usage lines
MARK = re.compile(r"(<!-- parameters (\w+) -->\n)(.*?)(<!-- end parameters -->)", re.S)
PREAMBLE = """# Command-line reference

Generated from the parsers by `python -m biped_gait.reference_docs` (a test checks it is current):
every entry point, every verb, every option with its default. Conventions of every command:

- Angles are in degrees on the command line (`--alpha-deg`, `--alpha-deg-range START STOP STEP`);
  everything inside, the JSON and the ROS interfaces are SI with radians.
- **The gait options** are one vocabulary (`biped_gait/gait_options.py`), the same on every verb
  that solves gaits, on the planner's service and action and on the simulator's parameters, with
  the same names and defaults. No sentinels: `--friction nan` (the default) is the parameter
  set's coefficient, `inf` no friction cone, `0` a frictionless floor (refused); a bound of `inf`
  is none; a margin of 0 is none. A gait that meets the limits but not the margins
  (`--min-clearance`, `--friction-margin`, `--rate-bound`) is reported as such, and not admissible.
- `--json PATH` writes the verb's result as JSON (`-`: standard output; the text then goes to
  standard error); `--out` is where the verb writes its files.
- Bad input is one line on standard error and exit status 2, before any work (output paths
  included); a gait that is not admissible, or a study with no admissible gait, exits with status
  1; Ctrl-C exits with 130 (a sweep keeps the gaits it solved). Warnings are one line each.
"""


def _actions(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction))]


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _default(action: argparse.Action) -> str:
    if action.option_strings and action.nargs == 0:
        return ""
    value = action.default
    if value is None or value is argparse.SUPPRESS:
        return ""
    if isinstance(value, (list, tuple)):
        return " ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _helps(parser: argparse.ArgumentParser) -> dict[str, str]:
    """The one-line help of each subcommand, by name."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return {choice.dest: choice.help or "" for choice in action._choices_actions}
    return {}


def _options_table(parser: argparse.ArgumentParser) -> list[str]:
    rows = ["| argument | what |", "|---|---|"]
    for action in _actions(parser):
        names = ", ".join(f"`{s}`" for s in action.option_strings) or f"`{action.metavar or action.dest}`"
        metavar = action.metavar if isinstance(action.metavar, str) else " ".join(action.metavar or ())
        if action.option_strings and action.nargs != 0 and (metavar or action.choices):
            names += f" {metavar or '{' + ','.join(action.choices) + '}'}"
        choices = f" ({', '.join(action.choices)})" if action.choices and not action.option_strings else ""
        rows.append(f"| {_cell(names)} | {_cell((action.help or '') + choices)} |")
    return rows


def _section(name: str, parser: argparse.ArgumentParser, level: int, summary: str = "") -> list[str]:
    lines = ["", f"{'#' * level} `{name}`", ""]
    text = parser.description or summary
    if text:
        lines += [text, ""]
    parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=USAGE_WIDTH)  # the same on any terminal
    lines += ["```", parser.format_usage().strip(), "```", ""]
    if _actions(parser):
        lines += _options_table(parser)
    helps = _helps(parser)
    for verb, sub in _subcommands(parser).items():
        lines += _section(f"{name} {verb}", sub, level + 1, helps.get(verb, ""))
    return lines


def option_matrix() -> list[str]:
    """The verb x gait-option table: which verb takes which option, and its default there."""
    top = _subcommands(build_parser())
    header = "| verb | " + " | ".join(f"`{o.cli_flag}`" for o in OPTIONS) + " |"
    rows = [header, "|---|" + "---|" * len(OPTIONS)]
    for verb in GAIT_VERBS:
        parser = top[verb.split()[0]]
        if " " in verb:
            parser = _subcommands(parser)[verb.split()[1]]
        by_dest = {a.dest: a for a in _actions(parser)}
        cells = [_default(by_dest[o.name]) if o.name in by_dest else "-" for o in OPTIONS]
        rows.append(f"| `{verb}` | " + " | ".join(_cell(c) or "(none)" for c in cells) + " |")
    return rows


def cli_page() -> str:
    """The text of docs/cli.md."""
    from .analysis.cli import build_parser as analyze_parser
    from .ros.launch import build_parser as launch_parser
    from .ros.replay import build_parser as replay_parser

    lines = [PREAMBLE, "## The gait options on every verb that solves gaits", "",
             "Each cell is the option's default on that verb (the same everywhere; `atlas build` builds an atlas per "
             "mode, so its `--mode` takes both by default). `nan` friction: the parameter set's coefficient.", ""]
    lines += option_matrix()
    lines += _section("biped-gait", build_parser(), 2)
    for parser in (launch_parser(), replay_parser(), analyze_parser()):
        lines += _section(parser.prog, parser, 2)
    lines += ["", "The nodes (`biped-gait-planner`, `biped-gait-simulator`) take ROS parameters: see "
              "[ros.md](ros.md#parameters)."]
    return "\n".join(lines).replace("\n\n\n", "\n\n") + "\n"


def parameter_table(params: Sequence) -> str:
    """A node's parameters as a Markdown table (``parameters.Param`` rows)."""
    rows = ["| parameter | default | range | set at run time | what |", "|---|---|---|---|---|"]
    for p in params:
        rows.append(f"| `{p.name}` | `{p.default!r}` | {_cell(p.bounds())} | {'yes' if p.dynamic else ''} | "
                    f"{_cell(p.description)} |")
    return "\n".join(rows) + "\n"


def ros_page(text: str) -> str:
    """``text`` (docs/ros.md) with its generated parameter tables made anew."""
    from .ros.planner_node import NODE_NAME as PLANNER, PARAMETERS as PLANNER_PARAMETERS
    from .ros.simulator_node import NODE_NAME as SIMULATOR, PARAMETERS as SIMULATOR_PARAMETERS

    tables = {PLANNER: parameter_table(PLANNER_PARAMETERS), SIMULATOR: parameter_table(SIMULATOR_PARAMETERS)}
    return MARK.sub(lambda m: m.group(1) + tables[m.group(2)] + m.group(4), text)


def main() -> int:
    """Rewrite docs/cli.md and the parameter tables of docs/ros.md."""
    CLI_PAGE.write_text(cli_page())
    ROS_PAGE.write_text(ros_page(ROS_PAGE.read_text()))
    print(f"written: {CLI_PAGE}, {ROS_PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
