"""The nodes' ROS parameters as tables: each with its default, a description naming its unit,
and its range where rclpy has one (``ParameterDescriptor`` ranges) or its choices. One table
serves to declare them (a bad value or type is one line, ``ValueError``), to print ``--help``
without starting ROS, and to check a ROS 2 parameters file before rcl parses it."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException, ParameterException
from rclpy.node import Node

from ..core.model.text import clip
from ..core.model.yaml_files import load_yaml_file

PARAMS_KEY = "ros__parameters"
TYPE_NAMES = {bool: "true or false", int: "an integer", float: "a floating-point number (e.g. 1.0, not 1)",
              str: "a string"}


@dataclass(frozen=True)
class Param:
    """One read-only ROS parameter: ``description`` names its unit; ``low``/``high`` bound a
    number (inclusive; a ``ParameterDescriptor`` range); ``choices`` list a string's values;
    ``infinite``: a float may be +-inf (never NaN)."""

    name: str
    default: bool | int | float | str
    description: str
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] = ()
    infinite: bool = False

    def descriptor(self) -> ParameterDescriptor:
        """The descriptor rclpy checks a value against (read-only, with the range if any)."""
        text = self.description + (f"; one of {', '.join(self.choices)}" if self.choices else "")
        descriptor = ParameterDescriptor(description=text, read_only=True)
        if self.low is not None and isinstance(self.default, float):
            descriptor.floating_point_range = [FloatingPointRange(from_value=float(self.low), to_value=float(self.high))]
        elif self.low is not None and isinstance(self.default, int) and not isinstance(self.default, bool):
            descriptor.integer_range = [IntegerRange(from_value=int(self.low), to_value=int(self.high), step=1)]
        return descriptor

    def bounds(self) -> str:
        """The range or choices as text ('' if free)."""
        if self.choices:
            return "one of " + ", ".join(self.choices)
        return f"in [{self.low:g}, {self.high:g}]" if self.low is not None else ""

    def check(self, value) -> None:
        """``ValueError`` (one line) if ``value`` is not allowed (what rclpy does not check)."""
        if isinstance(value, float) and (math.isnan(value) or math.isinf(value) and not self.infinite):
            raise ValueError(f"parameter {self.name}: must be a finite number, got {value}")
        if self.choices and value not in self.choices:
            raise ValueError(f"parameter {self.name}: must be {self.bounds()}, got {clip(repr(value))}")


def declare(node: Node, params: Sequence[Param]) -> dict[str, object]:
    """Declare ``params`` on ``node`` (command-line and file overrides applied) and return
    their values by name; ``ValueError`` with one line for a value of the wrong type or out of
    its range."""
    values = {}
    overrides = getattr(node, "_parameter_overrides", {})  # for the message only
    for param in params:
        given = overrides[param.name].value if param.name in overrides else None
        try:
            value = node.declare_parameter(param.name, param.default, param.descriptor()).value
        except InvalidParameterTypeException:
            raise ValueError(f"parameter {param.name}: expected {TYPE_NAMES[type(param.default)]}, "
                             f"got {clip(repr(given))}") from None
        except ParameterException:
            raise ValueError(f"parameter {param.name}: must be {param.bounds()} ({param.description}), "
                             f"got {clip(repr(given))}") from None
        param.check(value)
        values[param.name] = value
    return values


def help_text(program: str, summary: str, params: Sequence[Param]) -> str:
    """``--help`` of a node's entry point: usage, what it does, and every parameter."""
    lines = [f"usage: {program} [--ros-args -p NAME:=VALUE ... | --params-file FILE]", "", summary, "",
             "parameters (read-only; a bad value exits with status 2):"]
    for p in params:
        bounds = f", {p.bounds()}" if p.bounds() else ""
        lines.append(f"  {p.name} (default {p.default!r}{bounds}): {p.description}")
    return "\n".join(lines)


def _check_section(section: object, where: str) -> None:
    """A node's section: ``ros__parameters`` mapping, or namespaces holding such sections."""
    if not isinstance(section, dict) or not section:
        raise ValueError(f"{where}: expected a mapping with {PARAMS_KEY}")
    for key, value in section.items():
        inner = f"{where}.{key}"
        if key == PARAMS_KEY:
            if not isinstance(value, dict):
                raise ValueError(f"{inner}: expected a mapping of parameter names to values")
            _check_values(value, inner)
        else:
            _check_section(value, inner)


def _check_values(values: dict, where: str) -> None:
    for name, value in values.items():
        if isinstance(value, dict):
            _check_values(value, f"{where}.{name}")
        elif isinstance(value, list):
            if len({type(v) for v in value}) > 1 or any(isinstance(v, (dict, list)) or v is None for v in value):
                raise ValueError(f"{where}.{name}: a list must hold values of one simple type")
        elif value is None:
            raise ValueError(f"{where}.{name}: no value")


def check_parameters_file(path: str | Path) -> dict:
    """The ROS 2 parameters file ``path``, read with the YAML limits and checked for the shape
    rcl expects (node sections holding ``ros__parameters``); ``ValueError`` with one line."""
    document = load_yaml_file(path, "parameters file")
    if not isinstance(document, dict) or not document:
        raise ValueError(f"parameters file {path}: expected a mapping of node names to their {PARAMS_KEY}")
    for node, section in document.items():
        _check_section(section, f"parameters file {path}: {node}")
    return document
