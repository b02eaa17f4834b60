"""ROS 2 message definitions (``ros2msg`` schema text) and type description hashes for MCAP
recording.

A schema is the type's definition followed by each type it uses, after a line of 80 ``=`` and
``MSG: pkg/Type``. Definitions come from the ``.msg`` files installed in the ament prefixes
(the venv here). Field types are written fully qualified, so readers need no package context.
Only message types are recorded: the generated service and action parts (``PlanGait_Request``
...) have names that MCAP's ROS 2 readers refuse. Works without rosidl_runtime_py, which is not
installable here. Type hashes ('RIHS01_...', what rclpy reports for a topic's type and rosbag2
writes as ``type_description_hash``) come from the type descriptions rosidl installs beside the
definitions (``share/<pkg>/msg/<Type>.json``).
"""

from __future__ import annotations

import json
import os
import re
import sys
from functools import lru_cache
from pathlib import Path

PRIMITIVES = {
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
    "int32", "uint32", "int64", "uint64", "string", "wstring",
}
SEPARATOR = "=" * 80
_FIELD = re.compile(r"^(?P<type>[A-Za-z0-9_/]+(?:<=\d+)?)(?P<array>\[[^\]]*\])?\s+(?P<rest>\S.*)$")


def type_name(msg_or_class) -> str:
    """'pkg/msg/Type' (or srv/action) of an rclpy message object or class."""
    cls = msg_or_class if isinstance(msg_or_class, type) else type(msg_or_class)
    parts = cls.__module__.split(".")
    return f"{parts[0]}/{parts[1]}/{cls.__name__}"


def _prefixes() -> list[Path]:
    """AMENT_PREFIX_PATH, then this interpreter's prefix (the venv holds the wheels' share/)."""
    paths = [Path(p) for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    paths.append(Path(sys.prefix))
    return paths


def _find(pkg: str, kind: str, filename: str) -> str:
    """Text of share/<pkg>/<kind>/<filename> in the first ament prefix that has it."""
    for prefix in _prefixes():
        path = prefix / "share" / pkg / kind / filename
        if path.is_file():
            return path.read_text()
    raise LookupError(f"no definition of {pkg}/{kind}/{filename} in {[str(p) for p in _prefixes()]}")


@lru_cache(maxsize=None)
def type_hash(datatype: str) -> str:
    """The type description hash ('RIHS01_...') of 'pkg/msg/Type'; '' if no type description
    is installed for it."""
    parts = datatype.split("/")
    pkg, name = parts[0], parts[-1]
    try:
        hashes = json.loads(_find(pkg, "msg", f"{name}.json"))["type_hashes"]
    except (LookupError, ValueError, TypeError):
        return ""
    full = f"{pkg}/msg/{name}"
    return next((h["hash_string"] for h in hashes if h.get("type_name") == full), "")


def _raw_definition(pkg: str, name: str) -> str:
    """Definition text of pkg's message type ``name``."""
    return _find(pkg, "msg", f"{name}.msg")


def _qualify(pkg: str, base_type: str) -> str | None:
    """Fully qualified 'pkg/Type' of a field's base type, or None for a primitive."""
    bare = base_type.split("<=")[0]
    if bare in PRIMITIVES:
        return None
    if bare == "Header":
        return "std_msgs/Header"
    if "/" in bare:
        parts = bare.split("/")
        return f"{parts[0]}/{parts[-1]}"
    return f"{pkg}/{bare}"


def _normalize(pkg: str, text: str) -> tuple[str, list[str]]:
    """Comments dropped, field types qualified; returns (text, dependencies in order)."""
    lines, deps = [], []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        match = _FIELD.match(line)
        if match is None:
            raise ValueError(f"cannot parse message definition line {raw!r}")
        dep = _qualify(pkg, match["type"])
        if dep is None:
            lines.append(line)
            continue
        if dep not in deps:
            deps.append(dep)
        lines.append(f"{dep}{match['array'] or ''} {match['rest']}")
    return "\n".join(lines), deps


@lru_cache(maxsize=None)
def schema_text(datatype: str) -> str:
    """The full ``ros2msg`` schema of 'pkg/kind/Type' (or 'pkg/Type'), dependencies included."""
    parts = datatype.split("/")
    pkg, name = parts[0], parts[-1]
    main, pending = _normalize(pkg, _raw_definition(pkg, name))
    blocks, seen = [main], set()
    while pending:
        dep = pending.pop(0)
        if dep in seen:
            continue
        seen.add(dep)
        dep_pkg, dep_name = dep.split("/")
        text, more = _normalize(dep_pkg, _raw_definition(dep_pkg, dep_name))
        blocks.append(f"{SEPARATOR}\nMSG: {dep}\n{text}")
        pending.extend(d for d in more if d not in seen)
    return "\n".join(blocks) + "\n"
