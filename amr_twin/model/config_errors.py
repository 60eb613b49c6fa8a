"""A parameter file's validation error in the project's words: pydantic's first error as one line
naming the field and what is allowed (:func:`validation_message`): the range with its open ends
and unit, the number of values of a vector, the kind of value expected."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ValidationError

from amr_twin.model.config_leaves import field_range


def validation_message(exc: ValidationError, model: type[BaseModel]) -> str:
    """``exc``'s first error as ``<dotted field>: <what is wrong and what is allowed>``."""
    err = exc.errors()[0]
    loc = [str(p) for p in err["loc"] if not isinstance(p, int)]
    msg = err["msg"].replace("Value error, ", "")
    value = err.get("input")
    if any(k in (err.get("ctx") or {}) for k in ("ge", "gt", "le", "lt")):
        lo, hi, unit = field_range(model, loc)
        if (lo, hi) == ("-inf", "inf"):  # element constraint of a vector
            ctx = err["ctx"]
            lo = ctx.get("ge", ctx.get("gt", lo))
            hi = ctx.get("le", ctx.get("lt", hi))
        left, right = _open_ends(model, loc, err["ctx"])
        msg = (
            f"{value!r} is out of range: allowed {'(' if left else '['}{lo}, "
            f"{hi}{')' if right else ']'} {unit}"
        ).rstrip()
    elif err["type"] == "finite_number":
        msg = f"{value!r}: must be a finite number"
    elif err["type"] in ("missing", "too_short", "too_long") and isinstance(value, (list, tuple)):
        size = _tuple_size(model, loc)  # a fixed-size vector given another number of values
        msg = f"{list(value)!r} has {len(value)} value(s); it takes {size}" if size else msg
    elif err["type"] == "missing":  # pydantic's "Field required"
        msg = "missing: give its {value, unit, source} leaf"
    elif err["type"] in (
        "dict_type",
        "model_type",
        "model_attributes_type",
    ):  # "a valid dictionary or instance of"
        msg = f"{value!r} is not a section: give its parameters as keys"
    elif err["type"] in _KINDS:  # "Input should be a valid number, unable to parse ..."
        msg = f"{value!r} is not {_KINDS[err['type']]}"
    return f"{'.'.join(loc)}: {msg}" if loc else msg


_KINDS = {
    "float_parsing": "a number",
    "float_type": "a number",
    "int_parsing": "a whole number",
    "int_type": "a whole number",
    "int_from_float": "a whole number",
    "bool_parsing": "true or false",
    "bool_type": "true or false",
    "string_type": "a word",
    "tuple_type": "a list",
    "list_type": "a list",
}
"""pydantic's error types of a value of the wrong kind, and the kind in the project's words."""


def _open_ends(model: type[BaseModel], loc: list[str], ctx: dict) -> tuple[bool, bool]:
    """Whether the range of the field at ``loc`` excludes its low and its high end (``gt``, ``lt``):
    an exclusive bound was printed as ``[0.0, 3.0]`` for a refused 0."""
    field: Any = None
    for key in loc:
        fields = getattr(model, "model_fields", None) or {}
        field = fields.get(key)
        if field is None:
            return "gt" in ctx, "lt" in ctx
        model = field.annotation
    metadata = getattr(field, "metadata", ())
    return (
        any(getattr(m, "gt", None) is not None for m in metadata) or "gt" in ctx,
        any(getattr(m, "lt", None) is not None for m in metadata) or "lt" in ctx,
    )


def _tuple_size(model: type[BaseModel], loc: list[str]) -> int | None:
    """The number of values of the fixed-size tuple field at ``loc`` (None: not one)."""
    import typing

    annotation: Any = model
    for key in loc:
        fields = getattr(annotation, "model_fields", None)
        if not fields or key not in fields:
            return None
        annotation = fields[key].annotation
    args = typing.get_args(annotation)
    return (
        len(args)
        if typing.get_origin(annotation) is tuple and args and Ellipsis not in args
        else None
    )
