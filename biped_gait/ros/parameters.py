"""The nodes' ROS parameters as tables: each with its default, a description naming its unit,
and its range where rclpy has one (``ParameterDescriptor`` ranges) or its choices. One table
serves to declare them (a bad value or type, or a parameter the node does not have, is one
line, ``ValueError``), to print ``--help`` without starting ROS, to check a ROS 2 parameters
file before rcl parses it, and to take changes at run time through the parameter services: a
``dynamic`` parameter is applied by the node's handler (refused with its reason if it cannot
be), every other one is read-only (read at start; rclpy refuses a change with a reason)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.exceptions import InvalidParameterTypeException, ParameterException
from rclpy.node import Node

from ..core.model.text import clip
from ..core.model.yaml_files import load_yaml_file

PARAMS_KEY = "ros__parameters"
TYPE_NAMES = {bool: "true or false", int: "an integer", float: "a floating-point number (e.g. 1.0, not 1)",
              str: "a string"}
Handler = Callable[[str, object], None]  # applies a dynamic parameter's new value; ValueError: refused


@dataclass(frozen=True)
class Param:
    """One ROS parameter: ``description`` names its unit; ``low``/``high`` bound a number
    (inclusive; a ``ParameterDescriptor`` range); ``choices`` list a string's values;
    ``finite``: a float must be finite (else NaN and inf are values of their own, as the gait
    vocabulary's); ``dynamic``: settable at run time (else read-only)."""

    name: str
    default: bool | int | float | str
    description: str
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] = ()
    finite: bool = True
    dynamic: bool = False

    def descriptor(self) -> ParameterDescriptor:
        """The descriptor rclpy checks a value against (read-only unless dynamic, with the range
        if any)."""
        text = self.description + (f"; one of {', '.join(self.choices)}" if self.choices else "")
        text += "; settable at run time" if self.dynamic else "; read at start"
        descriptor = ParameterDescriptor(description=text, read_only=not self.dynamic)
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
        if self.finite and isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"parameter {self.name}: must be a finite number, got {value}")
        if self.choices and value not in self.choices:
            raise ValueError(f"parameter {self.name}: must be {self.bounds()}, got {clip(repr(value))}")


def declare(node: Node, params: Sequence[Param], on_change: Handler | None = None) -> dict[str, object]:
    """Declare ``params`` on ``node`` (command-line and file overrides applied) and return
    their values by name; ``ValueError`` with one line for a value of the wrong type or out of
    its range, or for an override of a parameter the node does not have. ``on_change`` applies
    a new value of a dynamic parameter set at run time (its ``ValueError`` refuses the change,
    with its message as the reason)."""
    values = {}
    overrides = getattr(node, "_parameter_overrides", {})  # what the command line and files gave
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
    unknown = sorted(name for name in overrides if not node.has_parameter(name))
    if unknown:
        raise ValueError(f"unknown parameter {clip(unknown[0])} for {node.get_name()} (its parameters: "
                         f"{', '.join(p.name for p in params)}; see --help)")
    node.add_on_set_parameters_callback(_setter({p.name: p for p in params if p.dynamic}, on_change))
    return values


def _setter(dynamic: dict[str, Param], on_change: Handler | None):
    """The on-set callback: a dynamic parameter checked and applied by ``on_change``; the others
    are refused by rclpy before (read-only) unless declared by rclpy itself."""

    def on_set(parameters) -> SetParametersResult:
        for parameter in parameters:
            param = dynamic.get(parameter.name)
            if param is None:
                continue
            try:
                param.check(parameter.value)
                if on_change is not None:
                    on_change(parameter.name, parameter.value)
            except ValueError as exc:
                return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    return on_set


def help_text(program: str, summary: str, params: Sequence[Param]) -> str:
    """``--help`` of a node's entry point: usage, what it does, and every parameter."""
    lines = [f"usage: {program} [--ros-args -p NAME:=VALUE ... | --params-file FILE]", "", summary, "",
             "parameters (a bad value or an unknown name exits with status 2; * settable at run time through the "
             "parameter services, the others read at start):"]
    for p in params:
        bounds = f", {p.bounds()}" if p.bounds() else ""
        lines.append(f"  {p.name}{' *' if p.dynamic else ''} (default {p.default!r}{bounds}): {p.description}")
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
