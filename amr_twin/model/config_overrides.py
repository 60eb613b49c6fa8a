"""Overrides of the parameter file (``--params FILE``, ``--set key=value``, a command's own
options), each refusal naming who gave the value.

:func:`parse_assignment` reads one ``--set``; :func:`check_assignment` refuses, before the schema
sees it, a key that is no parameter (with the nearest names), a section given a value, and a value
of the wrong kind (a bool or a word for a number, a list of another length); :class:`Blame`
remembers who set each key, so that a value the schema refuses is reported as ``--set
wheel.radius_m=5: ...``, ``--params FILE: ...`` or ``--payload-kg 1e6: ...``, not as a bare key.
"""

from __future__ import annotations

import difflib
from typing import Any

from amr_twin.model.config_leaves import ConfigError


def parse_assignment(text: str) -> tuple[str, Any]:
    """Parse ``key=value`` (value in YAML syntax, e.g. ``payload.xy_m=[0.1,0]``)."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise ConfigError(
            f"--set {text!r}: expected KEY=VALUE with a parameter's dotted key, e.g. "
            "--set wheel.radius_m=0.1"
        )
    import yaml  # only for --set: off the start-up of the other commands

    try:
        value = yaml.safe_load(raw)
    except yaml.YAMLError:
        raise ConfigError(
            f"--set {text!r}: cannot read the value {raw!r} (YAML: a number, true/false, "
            "[a, b] or a word)"
        ) from None
    if isinstance(value, str):  # YAML 1.1 reads 1e6 as a word
        try:
            value = float(value)
        except ValueError:
            pass
    return key.strip(), value


def set_path(tree: dict, dotted: str, value: Any) -> None:
    """Replace the value at ``dotted`` of a nested tree; ConfigError if there is none."""
    keys = dotted.split(".")
    node = tree
    for k in keys[:-1]:
        if not isinstance(node.get(k), dict):
            raise ConfigError(f"{dotted}: unknown key")
        node = node[k]
    if keys[-1] not in node:
        raise ConfigError(f"{dotted}: unknown key")
    node[keys[-1]] = value


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "true or false"
    if isinstance(value, (int, float)):  # NaN and infinities too: refused later as not finite
        return "a number"
    if isinstance(
        value, (list, tuple)
    ):  # its length is the schema's to judge (some vectors have any)
        return "a list of numbers" if all(_kind(v) == "a number" for v in value) else "a list"
    if value is None:
        return "nothing"  # --set key= (was "NoneType")
    return (
        "a word"
        if isinstance(value, str)
        else "a mapping"
        if isinstance(value, dict)
        else type(value).__name__
    )


def check_assignment(text: str, key: str, value: Any, meta: dict[str, dict], plain: dict) -> None:
    """Refuse ``--set text`` unless ``key`` is a parameter (a key of ``meta``) and ``value`` is of
    its kind.

    ``plain`` is the parameter file's tree of plain values (its value tells the kind,
    :func:`check_kind`)."""
    if key not in meta:
        inside = [k for k in meta if k.startswith(key + ".")]
        if inside:
            shown = ", ".join(inside[:4]) + (", ..." if len(inside) > 4 else "")
            raise ConfigError(
                f"--set {text!r}: {key} is a section, not a parameter; set one of its parameters "
                f"({shown})"
            )
        names = {k: k for k in meta} | {k.rsplit(".", 1)[-1]: k for k in meta}
        near = [names[n] for n in difflib.get_close_matches(key, list(names), n=3, cutoff=0.6)]
        hint = f"; did you mean {' or '.join(dict.fromkeys(near))}?" if near else ""
        raise ConfigError(
            f"--set {text!r}: {key!r} is not a parameter{hint} (the keys: models/amr/amr.yaml, "
            "e.g. wheel.radius_m)"
        )
    node: Any = plain
    for part in key.split("."):
        node = node[part]
    try:
        check_kind(key, value, meta, node)
    except ConfigError as exc:
        raise ConfigError(f"--set {text!r}: {exc}") from None


def check_kind(key: str, value: Any, meta: dict[str, dict], current: Any) -> None:
    """Refuse ``value`` for parameter ``key`` unless it is of the kind of its ``current`` value (a
    number for a number, a list of as many numbers for a vector, true/false for a switch, a word for
    a word)."""
    want, got = _kind(current), _kind(value)
    if want != got:
        unit = meta[key].get("unit")
        raise ConfigError(
            f"{key} takes {want}"
            + (f" ({unit})" if unit and unit != "-" else "")
            + f", not {got}"
            + (f" ({value!r})" if got in ("a word", "true or false") else "")
        )


class Blame:
    """Who set each parameter key: ``--set 'k=v'``, ``--params FILE`` or an option's label."""

    def __init__(self) -> None:
        self.by: dict[str, str] = {}

    def set(self, key: str, who: str) -> None:
        self.by[key] = who

    def message(self, text: str, file=None) -> str:
        """``text`` (``key: reason``) led by who set ``key``, or, for a section's rule
        (``uwb: anchors_y_m: ...``), who set the parameter of that section it names; when nobody
        did, by the parameter ``file`` (None: the robot's own, unnamed)."""
        key = text.split(":", 1)[0].split(",")[0].strip()
        who = self.by.get(key) or next(
            (
                w
                for k, w in self.by.items()
                if k.startswith(key + ".") and k.rsplit(".", 1)[-1] in text
            ),
            None,
        )
        who = who or (str(file) if file is not None else None)
        return f"{who}: {text}" if who else text
