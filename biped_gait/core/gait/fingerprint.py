"""What a gait atlas is tied to: the parameter set and the model code it was computed with.

``model_fingerprint`` hashes (SHA-256) the parameter set's values and the code of the core
modules that decide a gait's solution and verdict: their syntax trees without docstrings (so a
comment or a docstring does not make an atlas stale, a changed line of code does), the compiled
flow's source, and the atlas format version. ``source_fingerprint`` hashes the same files' bytes
as they are: an atlas records both, so that the atlas of this very code is recognized without
parsing it (a millisecond, where the syntax trees take tens), and one whose code differs only in
comments and docstrings still by its model fingerprint.
"""

from __future__ import annotations

import ast
import hashlib
import json
from dataclasses import asdict
from functools import lru_cache
from pathlib import Path

from ..model.params import BipedParams

ATLAS_FORMAT = 4
_CORE = Path(__file__).resolve().parents[1]
# The modules whose code decides a gait's solution and verdict, and the grid it is solved on (paths in the core).
MODEL_CODE = ("model/joints.py", "model/biped.py", "model/exchange.py", "gait/configurations.py", "dynamics/rk8_tableau.py", "dynamics/flow.py",
              "dynamics/hybrid.py", "dynamics/newton.py", "gait/bvp.py", "dynamics/impulses.py", "dynamics/samples.py",
              "gait/figures.py", "gait/admissibility.py", "gait/stability.py", "dynamics/settings.py",
              "gait/accuracy.py", "gait/richardson.py",
              "dynamics/native/flow.cpp", "dynamics/native/samples.cpp")


def _strip_docstrings(tree: ast.AST) -> ast.AST:
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(getattr(body[0], "value", None), ast.Constant) and isinstance(body[0].value.value, str):
            node.body = body[1:] or [ast.Pass()]
    return tree


def code_digest(head: str, names: tuple[str, ...]) -> str:
    """SHA-256 of ``head`` and of the core modules ``names`` (paths in the core), comments and
    docstrings left out of the Python ones."""
    digest = hashlib.sha256(f"{head}\n".encode())
    for name in names:
        text = (_CORE / name).read_text()
        if name.endswith(".py"):
            text = ast.dump(_strip_docstrings(ast.parse(text)))
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
