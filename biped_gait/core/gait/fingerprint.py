"""What a gait atlas is tied to: the parameter set and the model code it was computed with.

``model_fingerprint`` hashes (SHA-256) the parameter set's values and the code of the core
modules that decide a gait's solution and verdict: their tokens (``code_tokens``: without
comments, blank lines, indentation widths and docstrings, so a comment or a docstring does not
make an atlas stale, a changed line of code does, and the same code hashes the same on every
Python version), the compiled flow's source, and the atlas format version. ``source_fingerprint``
hashes the same files' bytes as they are: an atlas records both, so that the atlas of this very
code is recognized without tokenizing it, and one whose code differs only in comments and
docstrings still by its model fingerprint.
"""

from __future__ import annotations

import hashlib
import io
import json
import tokenize
from dataclasses import asdict
from functools import lru_cache
from pathlib import Path

from ..model.params import BipedParams

ATLAS_FORMAT = 4
_CORE = Path(__file__).resolve().parents[1]
# The modules whose code decides a gait's solution and verdict, and the grid it is solved on
# (paths in the core), with every core module they import (tests/test_fingerprint.py checks it).
MODEL_CODE = ("model/joints.py", "model/biped.py", "model/exchange.py", "model/rotations.py", "model/params.py",
              "model/text.py", "model/yaml_files.py", "gait/configurations.py", "dynamics/rk8_tableau.py",
              "dynamics/flow.py", "dynamics/hybrid.py", "dynamics/newton.py", "gait/bvp.py", "dynamics/impulses.py",
              "dynamics/samples.py", "gait/figures.py", "gait/admissibility.py", "gait/stability.py",
              "dynamics/settings.py", "gait/accuracy.py", "gait/richardson.py", "gait/gait.py", "gait/margins.py",
              "gait/views.py", "dynamics/native/flow.cpp", "dynamics/native/samples.cpp")
# Tokens that carry no meaning of their own (an INDENT's and a DEDENT's do: they are kept, without
# their width); a NEWLINE ends a statement, an NL a line within one or a blank line.
_NOISE = {tokenize.COMMENT, tokenize.NL, tokenize.ENCODING}
_MARKS = {tokenize.NEWLINE: "<NEWLINE>", tokenize.INDENT: "<INDENT>", tokenize.DEDENT: "<DEDENT>",
          tokenize.ENDMARKER: "<END>"}
# Python 3.12 splits an f-string into tokens of its own (PEP 701); 3.11 gives one STRING.
_FSTRING_START = getattr(tokenize, "FSTRING_START", None)
_FSTRING_END = getattr(tokenize, "FSTRING_END", None)


def code_tokens(text: str) -> list[str]:
    """The tokens of the Python source ``text``, as on every Python version: without comments,
    blank lines and line continuations, an indentation as a mark without its width, each
    f-string one token (its source), and without string statements (docstrings, and any other
    string alone on a statement, which does nothing)."""
    lines = text.splitlines(keepends=True)
    out: list[str] = []
    string_statement = 0  # how many tokens from the end are a string statement so far (0: none)
    depth, start = 0, (0, 0)  # f-string nesting, and where the outermost began
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type in _NOISE:
            continue
        if tok.type == _FSTRING_START:
            depth += 1
            start = tok.start if depth == 1 else start
            continue
        if depth:
            if tok.type == _FSTRING_END:
                depth -= 1
                if not depth:
                    out.append(_source(lines, start, tok.end))
                    string_statement = 0
            continue
        plain = tok.type == tokenize.STRING and "f" not in tok.string[:tok.string.find(tok.string[-1])].lower()
        if plain and (string_statement or not out or out[-1] in _MARKS.values()):
            string_statement += 1
        elif tok.type == tokenize.NEWLINE and string_statement:
            del out[-string_statement:]
            string_statement = 0
            continue
        else:
            string_statement = 0
        out.append(_MARKS.get(tok.type, tok.string))
    return out


def _source(lines: list[str], start: tuple[int, int], end: tuple[int, int]) -> str:
    """The source text from ``start`` to ``end`` (tokenize's (row from 1, column) positions)."""
    (r0, c0), (r1, c1) = start, end
    if r0 == r1:
        return lines[r0 - 1][c0:c1]
    return lines[r0 - 1][c0:] + "".join(lines[r0:r1 - 1]) + lines[r1 - 1][:c1]


def code_digest(head: str, names: tuple[str, ...]) -> str:
    """SHA-256 of ``head`` and of the core modules ``names`` (paths in the core), the Python
    ones by their tokens (``code_tokens``)."""
    digest = hashlib.sha256(f"{head}\n".encode())
    for name in names:
        text = (_CORE / name).read_text()
        if name.endswith(".py"):
            text = json.dumps(code_tokens(text))
        digest.update(f"{name}\n{text}\n".encode())
    return digest.hexdigest()


@lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """SHA-256 of the model code (``MODEL_CODE``), comments and docstrings left out."""
    return code_digest(f"atlas format {ATLAS_FORMAT}", MODEL_CODE)


@lru_cache(maxsize=1)
def source_digest() -> str:
    """SHA-256 of the model code's bytes (``MODEL_CODE``), comments and docstrings included."""
    digest = hashlib.sha256(f"atlas format {ATLAS_FORMAT}\n".encode())
    for name in MODEL_CODE:
        digest.update(f"{name}\n".encode() + (_CORE / name).read_bytes() + b"\n")
    return digest.hexdigest()


def _tied(params: BipedParams, code: str) -> str:
    """SHA-256 of ``params``' values (not its name) and of a digest of the code."""
    values = asdict(params)
    values.pop("name")
    text = json.dumps(values, sort_keys=True) + "\n" + code
    return hashlib.sha256(text.encode()).hexdigest()


def model_fingerprint(params: BipedParams) -> str:
    """SHA-256 of ``params``' values (not its name) and of the model code (``code_fingerprint``)."""
    return _tied(params, code_fingerprint())


def source_fingerprint(params: BipedParams) -> str:
    """SHA-256 of ``params``' values (not its name) and of the model code's bytes (``source_digest``)."""
    return _tied(params, source_digest())
