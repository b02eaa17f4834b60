"""Command-line parsing shared by the project's commands: one-line errors, output paths
checked before any work starts, and the gait vocabulary (``gait_options``) as arguments: the
gait's point (L, T, alpha as one value, a list or a range), every option, ``--json``."""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

from .gait_options import ALPHA_RANGE_DEG, OPTION_BY_NAME, OPTIONS, POINT, GaitOption, resolve_unset

STDOUT = "-"  # --json - writes to standard output
ONE, MANY, RANGE = "one", "many", "range"  # how a verb takes an axis of the point


class OneLineParser(argparse.ArgumentParser):
    """Bad usage is one line on stderr and exit status 2, like every other input error."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def _nearest_existing(path: Path) -> Path:
    """``path`` or its closest ancestor that exists."""
    path = path.absolute()
    while not path.exists() and path != path.parent:
        path = path.parent
    return path


def _check_folder_writable(folder: Path, what: str) -> None:
    """``ValueError`` unless ``folder`` can be written in or created (its closest existing
    ancestor is a folder this process may write in)."""
    existing = _nearest_existing(folder)
    if not existing.is_dir():
        raise ValueError(f"{what}: {existing} is not a folder")
    try:
        tempfile.TemporaryFile(dir=existing).close()  # what a write will meet (root, read-only mounts)
    except OSError as exc:
        raise ValueError(f"{what}: cannot write in {existing} ({exc.strerror or exc})") from None


def check_output_file(path: Path, what: str) -> None:
    """``ValueError`` (one line) unless a file can be written at ``path`` (its folder is
    created when written): checked before any work, so that nothing is lost at the end."""
    if path.is_dir():
        raise ValueError(f"{what} {path} is a folder, not a file")
    _check_folder_writable(path.parent, f"{what} {path}")


def check_output_folder(path: Path, what: str, force: bool) -> None:
    """``ValueError`` (one line) unless ``path`` is a folder that can be written in (created if
    missing) and is empty, or ``force`` allows replacing what it holds."""
    if path.exists() and not path.is_dir():
        raise ValueError(f"{what} {path} is a file, not a folder")
    if path.is_dir() and any(path.iterdir()) and not force:
        raise ValueError(f"{what} {path} is not empty (an earlier run?): give another folder, or --force to "
                         "replace its files")
    _check_folder_writable(path, f"{what} {path}")


def _help(option: GaitOption) -> str:
    unit = f" ({option.cli_unit})" if option.cli_unit else ""
    return f"{option.help}{unit}; default {option.default_text(cli=True)}"


def add_point(parser: argparse.ArgumentParser, step_length: str = ONE, period: str = ONE, alpha: str | None = ONE,
              alpha_default: str | None = None) -> None:
    """The gait's point: L (m), T (s) and alpha (deg), each as ``ONE`` value, ``MANY`` (a list
    or ``--NAME-range START STOP STEP``) or, for alpha, a ``RANGE`` only (``--alpha-deg-range``,
    default ``ALPHA_RANGE_DEG``); ``alpha`` None: the verb takes no amplitude; ``alpha_default``
    says in words what a list's absence means."""
    for option, how in zip(POINT, (step_length, period, alpha)):
        if how is None:
            continue
        flag, unit = option.cli_flag, option.cli_unit
        default = option.to_cli(option.default)
        in_words = alpha_default if option is POINT[2] else None
        if how == ONE:
            parser.add_argument(flag, type=float, default=default, metavar=unit.upper().replace("/", "_") or "V",
                                help=f"{option.help} ({unit}), default {default:g}")
            continue
        if how == MANY:
            group = parser.add_mutually_exclusive_group()
            group.add_argument(flag, nargs="+", type=float, metavar="V",
                               help=f"{option.help} ({unit}): values, default {in_words or f'{default:g}'}")
            target = group
        else:
            target = parser
        range_default = list(ALPHA_RANGE_DEG) if how == RANGE else None
        shown = f", default {' '.join(f'{v:g}' for v in ALPHA_RANGE_DEG)}" if how == RANGE else ""
        target.add_argument(f"{flag}-range", nargs=3, type=float, metavar=("START", "STOP", "STEP"),
                            default=range_default, help=f"{option.help} ({unit}): START to STOP inclusive, every STEP"
                            f"{shown}")


def add_gait_options(parser: argparse.ArgumentParser, modes: str = ONE, mode_default: tuple[str, ...] | None = None) -> None:
    """Every option of ``gait_options.OPTIONS``; ``modes``: ``ONE`` mode or ``MANY`` (a list,
    default ``mode_default`` or the vocabulary's one)."""
    group = parser.add_argument_group("gait options (the same on every verb, the service, the action and the "
                                      "simulator's parameters)")
    for option in OPTIONS:
        kwargs: dict = {"help": _help(option), "default": option.default}
        if option.choices:
            kwargs["choices"] = option.choices
        elif isinstance(option.default, float):
            kwargs["type"] = float
            kwargs["metavar"] = option.cli_unit.upper().replace("/", "_") or "V"
        if option.name == "mode" and modes == MANY:
            kwargs.update(nargs="+", default=list(mode_default or (option.default,)))
            kwargs["help"] = f"{option.help}; one or more, default {' '.join(kwargs['default'])}"
        group.add_argument(option.cli_flag, **kwargs)


def add_json(parser: argparse.ArgumentParser, what: str) -> None:
    """``--json PATH``: the verb's result as JSON (``-``: standard output; the text then goes
    to standard error)."""
    parser.add_argument("--json", metavar="PATH", help=f"write {what} as JSON (SI, radians) to this file ('-': "
                        "standard output, the text output then goes to standard error)")


def request_fields(args: argparse.Namespace, exclude: tuple[str, ...] = ("mode",)) -> dict[str, object]:
    """The ``GaitRequest`` fields of the gait options given (request units; a 0 that means unset
    replaced by what it stands for, ``gait_options.resolve_unset``), less ``exclude``."""
    return resolve_unset({o.name: o.from_cli(getattr(args, o.name)) for o in OPTIONS if o.name not in exclude})


def point_values(args: argparse.Namespace, name: str, default_range: tuple[float, float, float] | None = None
                 ) -> tuple[float, ...] | None:
    """The values (request units) of the point's axis ``name`` given as a list or a range;
    neither given: ``default_range`` (START, STOP, STEP in the command line's units) if any, else
    the vocabulary's default alone."""
    from .core.gait.chains import inclusive_range  # checked as the sweep checks it

    option = OPTION_BY_NAME[name]
    attr = (option.flag or name).replace("-", "_")
    values = getattr(args, attr, None)
    bounds = getattr(args, attr + "_range", None) or default_range if values is None else None
    if bounds is not None:
        values = inclusive_range(*bounds, name.replace("_", " "))
    return (option.default,) if values is None else tuple(option.from_cli(v) for v in values)


def alpha_range(args: argparse.Namespace) -> tuple[float, float, float]:
    """``--alpha-deg-range START STOP STEP`` in radians: (low, high, step), checked."""
    low, high, step = args.alpha_deg_range
    for value in (low, high, step):
        if not math.isfinite(value):
            raise ValueError(f"arm amplitude range must be finite numbers, got {low:g} {high:g} {step:g}")
    if not step > 0:
        raise ValueError(f"arm amplitude range step must be positive, got {step:g}")
    return math.radians(low), math.radians(high), math.radians(step)
