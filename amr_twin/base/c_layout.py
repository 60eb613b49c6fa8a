"""The C helpers' struct layouts checked against their ctypes twins when a helper is loaded.

A C helper whose structs Python builds or reads exports a table of them (``amr_layout``,
written with the macros of ``c_layout.h``: each struct's size, then each field's name,
offset and size in bytes). The Python wrapper registers the ctypes Structure of each C
struct next to its definition::

    register(C_SOURCE, battery_state=_State)

and :func:`amr_twin.base.native_build.load_helper` compares the two when it loads the helper:
the same field names in the same order, the same offsets and sizes, the same total size. A
field added, removed, retyped or moved on one side is found, and the helper is not used: its
Python twin runs, :func:`~amr_twin.base.native_build.native_status` says why, and a
``RuntimeWarning`` says so once. (A field squeezed into padding and listed on neither side
escapes the check: then nothing in Python reads or writes it either.)
"""

from __future__ import annotations

import ctypes
from pathlib import Path

LAYOUT_HEADER = Path(__file__).with_name("c_layout.h")
"""The macros a helper's table is written with (part of every helper's build key)."""
TABLE = "amr_layout"
"""The exported symbol: ``amr_layout_entry[]`` ended by a row whose ``type`` is NULL."""
MAX_ROWS = 1000
"""A table longer than this is taken for a missing end row."""

_registered: dict[str, dict[str, type[ctypes.Structure]]] = {}


class _Entry(ctypes.Structure):
    """``amr_layout_entry`` of c_layout.h (fixed: the check cannot check itself)."""

    _fields_ = [
        ("type", ctypes.c_char_p),
        ("field", ctypes.c_char_p),
        ("offset", ctypes.c_size_t),
        ("size", ctypes.c_size_t),
    ]


Layout = tuple[int, tuple[tuple[str, int, int], ...]]
"""A struct's size and its fields as (name, offset, size), bytes, in declaration order."""


def register(source: Path, **structs: type[ctypes.Structure]) -> None:
    """Declare the ctypes twins of the C structs of the helper ``source``: ``name=Structure`` with
    ``name`` the struct's typedef name in the C file."""
    _registered.setdefault(str(source), {}).update(structs)


def registered(source: Path) -> dict[str, type[ctypes.Structure]]:
    """The ctypes twins registered for ``source``, by C name."""
    return dict(_registered.get(str(source), {}))


def ctypes_layout(struct: type[ctypes.Structure]) -> Layout:
    """The layout ctypes gives ``struct``."""
    fields = tuple(
        (name, getattr(struct, name).offset, getattr(struct, name).size)
        for name, *_ in struct._fields_
    )
    return ctypes.sizeof(struct), fields


def c_layouts(lib: ctypes.CDLL) -> dict[str, Layout] | None:
    """The layouts in the helper's ``amr_layout`` table, by struct name; None without a table."""
    try:
        first = _Entry.in_dll(lib, TABLE)
    except ValueError:
        return None
    rows = ctypes.cast(ctypes.addressof(first), ctypes.POINTER(_Entry))
    sizes: dict[str, int] = {}
    fields: dict[str, list[tuple[str, int, int]]] = {}
    for i in range(MAX_ROWS):
        row = rows[i]
        if row.type is None:
            break
        name = row.type.decode()
        if row.field is None:
            sizes[name] = int(row.size)
        else:
            fields.setdefault(name, []).append((row.field.decode(), int(row.offset), int(row.size)))
    else:
        raise ValueError(f"{TABLE}: no end row within {MAX_ROWS} rows")
    return {
        name: (sizes.get(name, -1), tuple(fields.get(name, ())))
        for name in sizes.keys() | fields.keys()
    }


def layout_problem(source: Path, lib: ctypes.CDLL) -> str:
    """Why the helper ``lib`` built from ``source`` does not match its registered ctypes twins,
    or ``""`` when it does (or when nothing is registered for it)."""
    wanted = registered(source)
    if not wanted:
        return ""
    name = Path(source).name
    try:
        table = c_layouts(lib)
    except ValueError as exc:
        return f"{name}: {exc}"
    if table is None:
        return f"{name} exports no {TABLE} table for {', '.join(sorted(wanted))}"
    for struct_name, struct in wanted.items():
        if struct_name not in table:
            return f"{name}'s {TABLE} has no {struct_name}"
        problem = _difference(table[struct_name], ctypes_layout(struct))
        if problem:
            return f"{name}: {struct_name} {problem} ({struct.__qualname__} in Python)"
    return ""


def _difference(c: Layout, py: Layout) -> str:
    """The first difference of the C layout ``c`` and the ctypes layout ``py``, or ``""``."""
    (c_size, c_fields), (py_size, py_fields) = c, py
    c_names, py_names = [f[0] for f in c_fields], [f[0] for f in py_fields]
    for field in c_names:
        if field not in py_names:
            return f"has a field {field!r} its ctypes twin lacks"
    for field in py_names:
        if field not in c_names:
            return f"lacks the field {field!r} of its ctypes twin"
    if c_names != py_names:
        return f"fields in another order: C {c_names}, ctypes {py_names}"
    for (field, c_off, c_len), (_, py_off, py_len) in zip(c_fields, py_fields):
        if (c_off, c_len) != (py_off, py_len):
            return (
                f"field {field!r} at byte {c_off} of {c_len} in C, at {py_off} of {py_len} in "
                f"ctypes"
            )
    if c_size != py_size:
        return f"is {c_size} bytes in C, {py_size} in ctypes"
    return ""
