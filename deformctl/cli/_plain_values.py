"""Option values coerced without pydantic where the result is plainly pydantic's.

typer coerces every option and argument value through a pydantic ``TypeAdapter`` built on first
use, so a command that runs imports pydantic and builds an adapter per parameter: about 0.05 s
of CPU, a tenth of a short command (``population``, ``inspect``). Nearly every value a command
gets is plain: text for a ``str`` option, a default of the option's own type, a decimal number
for an ``int`` or ``float`` option. :func:`install` gives each parameter of a command a
:class:`PlainFirst` coercion that returns those values as the adapter would (:func:`plain_value`)
and hands anything else to typer's own coercion, built when first needed, so every error message
and every unusual value is typer's and pydantic's (``tests/cli/test_plain_values.py`` holds the
two side by side).
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING, Any, get_args, get_origin

from typer._coercion import build_runtime_param

if TYPE_CHECKING:  # pragma: no cover - annotations only
    from typer._click import Command, Context
    from typer._coercion import RuntimeParam, TypeDescriptor

#: what :func:`plain_value` returns for a value it leaves to typer's coercion
NOT_PLAIN: Any = object()

#: decimal integers as a command line writes them (no sign but minus, no leading zero, no ``_``)
_INT = re.compile(r"-?(?:0|[1-9][0-9]{0,17})")
#: decimal numbers in the same spelling, with an optional fraction and exponent
_FLOAT = re.compile(r"-?(?:0|[1-9][0-9]{0,17})(?:\.[0-9]{1,17})?(?:[eE][-+]?[0-9]{1,3})?")


def plain_value(annotation: Any, value: Any, multiple: bool) -> Any:
    """``value`` coerced to ``annotation`` as typer's pydantic adapter coerces it, for the plain
    cases: a ``str``, ``bool``, ``int`` or ``float`` value of that very type, a decimal text for
    an ``int`` or ``float``, a list of texts for a repeated ``list[str]`` option, a tuple of
    plain values for a fixed ``tuple[...]`` of those types; otherwise :data:`NOT_PLAIN`."""
    kind = type(value)
    if get_origin(annotation) is tuple and not multiple:
        items = get_args(annotation)
        if kind not in (list, tuple) or Ellipsis in items or len(items) != len(value):
            return NOT_PLAIN
        out = tuple(plain_value(item, v, False) for item, v in zip(items, value, strict=True))
        return NOT_PLAIN if any(v is NOT_PLAIN for v in out) else out
    if multiple:
        if annotation == list[str] and kind in (list, tuple):
            return list(value) if all(type(v) is str for v in value) else NOT_PLAIN
        return NOT_PLAIN
    if annotation in (str, bool) or (annotation in (int, float) and kind is annotation):
        return value if kind is annotation else NOT_PLAIN
    if kind is not str:
        return NOT_PLAIN
    if annotation is int and _INT.fullmatch(value):
        return int(value)
    if annotation is float and _FLOAT.fullmatch(value):
        number = float(value)
        return number if math.isfinite(number) else NOT_PLAIN
    return NOT_PLAIN


def _is_plain(descriptor: TypeDescriptor) -> bool:
    """Whether typer's coercion of ``descriptor`` is its plain one (a range aside): no parser,
    file, path or choice."""
    info = descriptor.parameter_info
    return (
        info.parser is None
        and getattr(info, "click_type", None) is None
        and descriptor.file_annotation is None
        and not descriptor.is_path
        and not descriptor.is_choice
    )


def _in_range(descriptor: TypeDescriptor, number: Any) -> bool:
    """Whether ``number`` is within the parameter's ``min`` and ``max`` (a number outside is left
    to typer, which refuses or clamps it)."""
    info = descriptor.parameter_info
    return (info.min is None or number >= info.min) and (info.max is None or number <= info.max)


class PlainFirst:
    """A parameter's coercion: :func:`plain_value`, else typer's own (built on first use)."""

    def __init__(self, descriptor: TypeDescriptor) -> None:
        self.descriptor = descriptor
        self._typer: RuntimeParam | None = None

    def coerce(self, value: Any, param: Any, ctx: Context) -> Any:
        """The value the command gets (typer's ``RuntimeParam.coerce``)."""
        multiple = bool(param.multiple or param.nargs == -1)
        if value is None:  # typer's own first step, before any adapter
            return () if multiple else None
        plain = plain_value(self.descriptor.annotation, value, multiple)
        if plain is not NOT_PLAIN and (
            not self.descriptor.is_ranged or _in_range(self.descriptor, plain)
        ):
            return plain
        if self._typer is None:
            self._typer = build_runtime_param(self.descriptor)
        return self._typer.coerce(value, param=param, ctx=ctx)


def install(command: Command | None) -> None:
    """Give each parameter of ``command`` whose coercion is plain (:func:`_is_plain`; a number
    in its range) and not yet built a :class:`PlainFirst` coercion; a parameter typer made
    otherwise is left alone."""
    for param in getattr(command, "params", ()):
        descriptor = getattr(param, "type_descriptor", None)
        if (
            descriptor is not None
            and getattr(param, "_runtime_param", False) is None
            and _is_plain(descriptor)
        ):
            param._runtime_param = PlainFirst(descriptor)
