"""What the verbs write besides their files: the result as JSON (``--json PATH``, ``-`` for
standard output) and the lines people read (standard output, or standard error when the JSON
goes to standard output)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..arguments import STDOUT, check_output_file
from ..core.gait.views import clean
from ..standard_output import drop_standard_output


def check_json(target: str | None) -> None:
    """``ValueError`` unless the ``--json`` target can be written (checked before any work)."""
    if target is not None and target != STDOUT:
        check_output_file(Path(target), "--json")


def json_text(document: object) -> str:
    """``document`` as JSON text: arrays as lists, NaN and infinities as null."""
    return json.dumps(clean(document), indent=1)


def write_json(target: str | None, document: object) -> Path | None:
    """Write ``document`` to the ``--json`` target (None: nowhere; ``-``: standard output,
    the one the process started with); returns the file written, if any."""
    if target is None:
        return None
    text = json_text(document) + "\n"
    if target == STDOUT:
        try:
            sys.__stdout__.write(text)
            sys.__stdout__.flush()
        except BrokenPipeError:
            drop_standard_output(sys.__stdout__)
        return None
    path = Path(target)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def write_model(text: str, out: Path | None) -> int:
    """A model file's ``text`` (URDF, MJCF) to ``out`` (its folder made; checked with
    ``check_output_file`` before the model was built) or, without ``--out``, standard output;
    exit status 0."""
    if out:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(text)
    else:
        sys.stdout.write(text)
    return 0

