"""Faults of the robot to inject into a run: ``KIND@T[:ARGS]`` specifications.

``amr-twin run ... --fault hall-left-dead@3`` (repeatable) or a mission's
``faults:`` list. ``T`` is the time of the fault, seconds from the start of the
run; ``ARGS`` a comma-separated list: the kind's parameter (bare, or by name) and
``for=S``, after which the fault clears (default: it lasts to the end)::

    hall-left-dead@3              the left wheel's SC signal stops changing
    hall-right-dead@3:a           one hall sensor (a, b or c) of the right wheel stuck
    hall-left-chatter@2:500       spurious SC pulses, 500 per second on average
    motor-right-stall@4:for=1.5   the right wheel jammed for 1.5 s
    rosserial-loss@2:0.3          30 % of the rosserial frames lost, both ways
    estop@5:for=2                 the e-stop pressed for 2 s

This module parses and validates (one-line :class:`FaultError` naming the
specification); :mod:`amr_twin.sim.fault_injector` applies the faults to a running twin.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

WHEEL_NAMES = ("left", "right")


@dataclass(frozen=True)
class KindSpec:
    """One fault kind: its parameter (name, unit, default, range) and what it does."""

    per_wheel: bool
    param: str | None
    default: float | str | None
    bounds: tuple[float, float] | tuple[str, ...] | None
    needs_sensors: bool
    summary: str


KINDS: dict[str, KindSpec] = {
    "hall-dead": KindSpec(
        True,
        "sensor",
        "all",
        ("all", "a", "b", "c"),
        False,
        "the wheel's SC speed signal stops changing at the Arduino (a broken SC wire or "
        "hall supply; with a, b or c one hall sensor is stuck and SC changes 60 times per "
        "revolution instead of 90); the motor itself keeps running",
    ),
    "hall-chatter": KindSpec(
        True,
        "rate_hz",
        200.0,
        (1.0, 20000.0),
        False,
        "spurious 20 us pulses on the wheel's SC line at RATE_HZ on average (Poisson, "
        "seeded): each adds two changes the firmware counts",
    ),
    "motor-stall": KindSpec(
        True,
        None,
        None,
        None,
        False,
        "the wheel jams (a seized hub, a stone): it cannot turn, whatever the motor and the "
        "ground do, until the fault clears",
    ),
    "wheel-lifted": KindSpec(
        True,
        None,
        None,
        None,
        False,
        "the wheel loses the ground (its tyre touches nothing): it spins freely, the "
        "casters carry the robot",
    ),
    "rosserial-loss": KindSpec(
        False,
        "p",
        1.0,
        (0.0, 1.0),
        False,
        "each rosserial frame (wheel_Command down, wheelN_Vel up) is lost with "
        "probability P (seeded); 1 cuts the link",
    ),
    "rosserial-latency": KindSpec(
        False,
        "latency_ms",
        100.0,
        (0.0, 10000.0),
        False,
        "every rosserial frame arrives LATENCY_MS later (USB/OS stalls)",
    ),
    "lidar-dead": KindSpec(
        False, None, None, None, True, "the LiDAR stops publishing scan (needs --sensors)"
    ),
    "imu-stuck": KindSpec(
        False,
        None,
        None,
        None,
        True,
        "imu/data_raw and imu/mag repeat the last sample before the fault, with new stamps "
        "(a hung I2C read; needs --sensors)",
    ),
    "battery-sag": KindSpec(
        False,
        "drop_v",
        10.0,
        (0.1, 42.0),
        False,
        "the battery's terminal voltage drops by DROP_V (a failing cell group, cold); the "
        "drivers' output scales with it",
    ),
    "battery-cut": KindSpec(
        False,
        None,
        None,
        None,
        False,
        "the drivers lose their supply (motor power line open): both wheels coast; the "
        "mini PC and the Arduino keep running",
    ),
    "estop": KindSpec(
        False,
        None,
        None,
        None,
        False,
        "the e-stop is pressed: its relays open both motors' phases, the wheels coast",
    ),
}
"""Fault kinds. Per-wheel kinds are written with the wheel: ``hall-left-dead``,
``motor-right-stall``."""

MAX_FAULTS = 64
"""Faults per run: more is a mistake (each is a clock event and a report entry)."""


class FaultError(ValueError):
    """A fault specification is invalid; the message is one line naming it."""


@dataclass(frozen=True)
class Fault:
    """One parsed fault.

    kind : key of :data:`KINDS` (``hall-dead`` ...); wheel : 0 left, 1 right, None;
    t_s : start, s; until_s : end, s (None: to the end of the run); value : the
    kind's parameter; text : the specification as given.
    """

    kind: str
    wheel: int | None
    t_s: float
    until_s: float | None
    value: float | str | None
    text: str

    @property
    def name(self) -> str:
        """The kind as written, with its wheel: ``hall-left-dead``."""
        if self.wheel is None:
            return self.kind
        first, _, rest = self.kind.partition("-")
        return f"{first}-{WHEEL_NAMES[self.wheel]}-{rest}"

    def describe(self) -> dict:
        """JSON-ready: the specification, its parts and what the kind does."""
        spec = KINDS[self.kind]
        out = {"fault": self.text, "kind": self.name, "t_s": self.t_s, "until_s": self.until_s}
        if self.wheel is not None:
            out["wheel"] = WHEEL_NAMES[self.wheel]
        if spec.param is not None:
            out[spec.param] = self.value
        out["description"] = spec.summary
        return out


def kind_names() -> list[str]:
    """Every kind as written on the command line."""
    names = []
    for kind, spec in KINDS.items():
        if spec.per_wheel:
            first, _, rest = kind.partition("-")
            names += [f"{first}-{w}-{rest}" for w in WHEEL_NAMES]
        else:
            names.append(kind)
    return names


def _split_kind(name: str) -> tuple[str, int | None] | None:
    if name in KINDS and not KINDS[name].per_wheel:
        return name, None
    parts = name.split("-")
    if len(parts) >= 3 and parts[1] in WHEEL_NAMES:
        kind = "-".join([parts[0], *parts[2:]])
        if kind in KINDS and KINDS[kind].per_wheel:
            return kind, WHEEL_NAMES.index(parts[1])
    return None


def _number(where: str, name: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise FaultError(f"{where}: {name}={text!r} is not a number") from None
    if not math.isfinite(value):
        raise FaultError(f"{where}: {name}={text} must be finite")
    return value


def parse_fault(text: str, where: str = "--fault") -> Fault:
    """``KIND@T[:ARGS]`` -> :class:`Fault`; :class:`FaultError` (one line) if invalid."""
    text = str(text).strip()
    at = f"{where} {text!r}"
    name, sep, rest = text.partition("@")
    if not sep:
        raise FaultError(f"{at}: expected KIND@T[:ARGS], e.g. hall-left-dead@3")
    found = _split_kind(name)
    if found is None:
        raise FaultError(f"{at}: unknown fault {name!r} (one of {', '.join(kind_names())})")
    kind, wheel = found
    spec = KINDS[kind]
    time_text, _, args_text = rest.partition(":")
    t_s = _number(at, "T", time_text.strip())
    if t_s < 0:
        raise FaultError(f"{at}: T={t_s:g} s must be >= 0")
    value, until_s = spec.default, None
    bare_seen = False
    for item in [a.strip() for a in args_text.split(",")] if args_text.strip() else []:
        key, eq, raw = item.partition("=")
        if not eq:
            key, raw = spec.param, item
            if key is None or bare_seen:
                raise FaultError(
                    f"{at}: unexpected argument {item!r}"
                    + (f" ({name} takes only for=S)" if spec.param is None else "")
                )
            bare_seen = True
        key = key.strip()
        if key == "for":
            duration = _number(at, "for", raw)
            if duration <= 0:
                raise FaultError(f"{at}: for={duration:g} s must be > 0")
            until_s = t_s + duration
        elif key == spec.param and spec.param is not None:
            value = _value(at, spec, raw.strip())
        else:
            allowed = ", ".join(([f"{spec.param}="] if spec.param else []) + ["for="])
            raise FaultError(f"{at}: unknown argument {key!r} (allowed: {allowed})")
    return Fault(kind, wheel, t_s, until_s, value, text)


def _value(at: str, spec: KindSpec, raw: str) -> float | str:
    if isinstance(spec.default, str):
        if raw not in spec.bounds:
            raise FaultError(f"{at}: {spec.param}={raw!r} must be one of {', '.join(spec.bounds)}")
        return raw
    value = _number(at, spec.param, raw)
    lo, hi = spec.bounds
    if not lo <= value <= hi or (spec.param == "p" and value == 0):
        low = "(0" if spec.param == "p" else f"[{lo:g}"
        raise FaultError(f"{at}: {spec.param}={value:g} must lie in {low}, {hi:g}]")
    return value


def parse_faults(
    texts, where: str = "--fault", duration_s: float | None = None, sensors: bool = True
) -> tuple[Fault, ...]:
    """Parse several specifications and check them against the run.

    ``duration_s``: a fault must start before the end of the run. ``sensors``:
    whether the IMU and LiDAR run (their faults need them).
    """
    texts = list(texts or [])
    if len(texts) > MAX_FAULTS:
        raise FaultError(f"{where}: {len(texts)} faults; at most {MAX_FAULTS} per run")
    faults = tuple(parse_fault(t, where) for t in texts)
    for f in faults:
        if duration_s is not None and f.t_s >= duration_s:
            raise FaultError(
                f"{where} {f.text!r}: T={f.t_s:g} s is not before the end of the run "
                f"({duration_s:g} s)"
            )
        if KINDS[f.kind].needs_sensors and not sensors:
            raise FaultError(f"{where} {f.text!r}: {f.name} needs the sensors (add --sensors)")
    return faults
