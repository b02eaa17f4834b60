"""Reading a YAML file a user hands in (a parameter set, a launch configuration) without
trusting it: a size limit checked before reading, UTF-8 text, a nesting limit checked on the
token stream before anything is built (the composer recurses), and ``yaml.safe_load``.
Every refusal is a ``ValueError`` with a one-line message.
"""

from __future__ import annotations

from pathlib import Path

import yaml

MAX_YAML_BYTES = 1024 * 1024  # a parameter file is about 1 kB, a launch file a few
MAX_YAML_DEPTH = 32  # nested mappings and sequences; the project's files use 4


def read_yaml_text(path: str | Path, what: str, limit: int = MAX_YAML_BYTES) -> str:
    """The text of the file ``path`` (``what`` names it in messages): refused if it is not a
    regular file, larger than ``limit`` bytes, unreadable, or not UTF-8."""
    path = Path(path)
    try:
        if not path.is_file():
            raise ValueError(f"{what} {path}: not a file")
        size = path.stat().st_size
        if size > limit:
            raise ValueError(f"{what} {path}: {size} bytes, more than the {limit} allowed")
        with open(path, "rb") as stream:
            data = stream.read(limit + 1)
    except OSError as exc:
        raise ValueError(f"{what} {path}: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise ValueError(f"{what} {path}: more than the {limit} bytes allowed")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{what} {path}: not UTF-8 text") from None


def parse_yaml(text: str, source: str) -> object:
    """``yaml.safe_load`` of ``text`` after checking its nesting depth; ``source`` names it."""
    depth = 0
    try:
        for token in yaml.scan(text):
            if isinstance(token, (yaml.BlockMappingStartToken, yaml.BlockSequenceStartToken,
                                  yaml.FlowMappingStartToken, yaml.FlowSequenceStartToken)):
                depth += 1
                if depth > MAX_YAML_DEPTH:
                    raise ValueError(f"{source}: nested more than {MAX_YAML_DEPTH} levels deep")
            elif isinstance(token, (yaml.BlockEndToken, yaml.FlowMappingEndToken, yaml.FlowSequenceEndToken)):
                depth -= 1
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        where = getattr(exc, "problem_mark", None)
        line = f" at line {where.line + 1}" if where is not None else ""
        raise ValueError(f"{source}: not valid YAML{line} ({exc.__class__.__name__})") from None
    except RecursionError:
        raise ValueError(f"{source}: nested too deeply") from None


def parse_package_yaml(text: str) -> object:
    """A YAML document the package ships (trusted, small): ``yaml.safe_load``'s values, parsed by
    libyaml when PyYAML has it (a tenth of the time of the Python parser)."""
    return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def load_yaml_file(path: str | Path, what: str, limit: int = MAX_YAML_BYTES) -> object:
    """The YAML document of the file ``path``, read and parsed with the limits above."""
    return parse_yaml(read_yaml_text(path, what, limit), f"{what} {path}")
