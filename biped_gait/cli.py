"""Command line ``biped-gait``: ``plan`` (one gait), the arm-swing study (``sweep``,
``optimize-arms``, ``figure``, ``maps``, ``push-study``, ``results-page``), ``atlas`` (build, show,
check the gait atlases), ``urdf`` and ``recover``. The parsers are ``cli_parser``'s (built from
the gait vocabulary); each verb's code is a module of ``commands``, imported when it runs, so
that ``--help`` and bad arguments cost no solver. Degrees at this edge; SI and radians inside.

Errors in the input print one line on stderr and exit with status 2, output paths included
(checked before any work: a folder that cannot be written, a sweep folder holding an earlier
run without ``--force``); a gait that does not converge or is not admissible is printed with
its reasons and exits with status 1, and so does a write that fails at the end (one line). An
interrupted verb (Ctrl-C) keeps what it can (a sweep its gaits) and exits with status 130. A
closed standard output (``| head -3``) is no error: what is printed after is dropped, quietly,
and the verb goes on (its files written).
Warnings (a parameter file without a current atlas, say) are one line each.
"""

from __future__ import annotations

import contextlib
import importlib
import sys
import warnings

from .arguments import STDOUT
from .cli_parser import PROG, build_parser
from .standard_output import QuietStdout

INTERRUPTED = 130  # exit status after Ctrl-C, as shells report it


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one line on stderr (no source line, no category)."""
    print(f"{PROG}: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``biped-gait``; returns the process exit status."""
    stdout = QuietStdout(sys.stdout)
    try:
        with contextlib.redirect_stdout(stdout):
            return _main(sys.argv[1:] if argv is None else argv)
    finally:
        stdout.flush()  # what is left in the buffer, where a closed reader is no error


def _main(argv: list[str]) -> int:
    try:
        args = build_parser(argv[0] if argv else None).parse_args(argv)
    except SystemExit as exc:  # --help (0), or bad usage (2, its one line printed)
        return int(exc.code or 0)
    warnings.showwarning = _one_line_warning
    module, function = args.run.split(":")
    to_stdout = getattr(args, "json", None) == STDOUT
    try:
        run = getattr(importlib.import_module(module), function)
        with contextlib.redirect_stdout(sys.stderr) if to_stdout else contextlib.nullcontext():
            return run(args)
    except ValueError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return INTERRUPTED
    except OSError as exc:  # a write at the end failed (disk full, folder removed meanwhile)
        print(f"{PROG}: error: {exc.filename or ''}: {exc.strerror or exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
