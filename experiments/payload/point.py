"""Payload sweep points: the payload's named positions, the ``--masses`` / ``--commands`` parsers
and :class:`Point`, one (mass, position, command) simulation with its result key and fingerprint.

Named positions put the payload box **flush with the deck's edges** (``front``:
against the front edge, ``front-left-corner``: in that corner...), the worst
placements that still lie on the deck; ``X:Y`` gives the box centre in metres.
A point's key names its file ``runs/<key>.json``; its fingerprint covers the
configuration, the firmware, the duration and what a row means (:data:`ROWS`), so a
resumed sweep redoes exactly the points whose inputs changed
(:mod:`.sweep`).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

from amr_twin.model.config import TwinConfig, with_values
from amr_twin.assembly.command import Command

POSITIONS = {
    "center": (0, 0),
    "front": (1, 0),
    "rear": (-1, 0),
    "left": (0, 1),
    "right": (0, -1),
    "front-left-corner": (1, 1),
    "front-right-corner": (1, -1),
    "rear-left-corner": (-1, 1),
    "rear-right-corner": (-1, -1),
}
MAX_MASSES = 1000  # masses per sweep: each is a simulation per position and command
# what a row means (in the fingerprint): 6 = with the true speed's steady error; 5 = ball speed as
# sqrt(ux^2 + uy^2) (C and Python alike); 4 = sampled on the loop's record grid in one call; 3 =
# with the rating judged by; 2 = support loads from the springs; 1: contact forces
ROWS = 6


def parse_masses(text: str) -> list[float]:
    """``"0:60:5"`` (start:stop:step, stop included) or ``"0,20,40"``, kg; ValueError with one
    line."""
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
        else:
            masses = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ValueError(
            f"--masses {text!r}: expected START:STOP:STEP or M1,M2,... in kg"
        ) from None
    if ":" in text:
        if not all(math.isfinite(v) for v in (start, stop, step)):
            raise ValueError(f"--masses {text!r}: START, STOP and STEP must be finite numbers (kg)")
        if stop < start:
            raise ValueError(
                f"--masses {text!r}: STOP {stop:g} kg is below START {start:g} kg: give START <= "
                f"STOP "
                f"(e.g. {stop:g}:{start:g}:{abs(step):g})"
            )
        if step <= 0:
            raise ValueError(f"--masses {text!r}: STEP {step:g} kg must be > 0")
        count = math.floor((stop - start) / step + 1e-9) + 1
        if count > MAX_MASSES:
            raise ValueError(
                f"--masses {text!r}: {count if count < 1e6 else f'{count:.3g}'} masses; at most "
                f"{MAX_MASSES} per sweep "
                "(each is one simulation per position and command)"
            )
        masses = [round(start + i * step, 6) for i in range(count)]
    if not masses:
        raise ValueError(f"--masses {text!r}: names no mass (START:STOP:STEP or M1,M2,... in kg)")
    if any(not math.isfinite(m) or m < 0 for m in masses):
        raise ValueError(f"--masses {text!r}: masses must be finite and >= 0 kg")
    if len(masses) > MAX_MASSES:
        raise ValueError(f"--masses: {len(masses)} masses; at most {MAX_MASSES} per sweep")
    return masses


def parse_command(text: str) -> Command:
    """One ``--commands`` entry -> Command (see :meth:`Command.parse`)."""
    return Command.parse(text, what="--commands")


def position_xy_m(cfg: TwinConfig, name: str) -> tuple[float, float]:
    """Payload centre of a named position (box flush with the deck edges) or of ``X:Y``, m."""
    if name in POSITIONS:
        dx, dy = POSITIONS[name]
        sx, sy = cfg.payload.size_m[0] / 2, cfg.payload.size_m[1] / 2
        inside = [
            _micrometres_inside(v)
            for v in (cfg.chassis.length_m / 2 - sx, cfg.chassis.width_m / 2 - sy)
        ]
        return dx * inside[0] + 0.0, dy * inside[1] + 0.0  # + 0.0: no -0.0
    try:
        x, y = (float(v) for v in name.split(":"))
    except ValueError:
        raise ValueError(
            f"--positions {name!r}: not one of {', '.join(POSITIONS)} nor X:Y in metres"
        ) from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"--positions {name!r}: X and Y must be finite numbers (m)")
    return x, y


def check_on_deck(cfg: TwinConfig, name: str) -> None:
    """Refuse a position ``X:Y`` whose payload box leaves ``cfg``'s deck (ValueError naming the
    deck's bounds); a drawn deck (``--samples``) may still be too small for it: that point is
    recorded invalid."""
    x, y = position_xy_m(cfg, name)
    hx = cfg.chassis.length_m / 2 - cfg.payload.size_m[0] / 2
    hy = cfg.chassis.width_m / 2 - cfg.payload.size_m[1] / 2
    if abs(x) > hx + 1e-9 or abs(y) > hy + 1e-9:
        raise ValueError(
            f"--positions {name!r}: the payload box ({cfg.payload.size_m[0]:g} x "
            f"{cfg.payload.size_m[1]:g} m) leaves the deck: |X| <= {hx:.3f} m and |Y| <= {hy:.3f} m"
        )


def check_masses(text: str, masses: list[float]) -> None:
    """Refuse masses above the schema's payload range: every such point was simulated as "invalid"
    and the answer read "unsafe already at 1000 kg" (ValueError naming ``--masses`` and the
    range)."""
    from amr_twin.model.config_leaves import field_range

    low, high, unit = field_range(TwinConfig, ["payload", "mass_kg"])
    over = [m for m in masses if m > high]
    if over:
        raise ValueError(
            f"--masses {text!r}: {over[0]:g} {unit} is above payload.mass_kg's allowed "
            f"[{low}, {high}] {unit}"
        )


def check_accepted(cfg: TwinConfig, text: str) -> None:
    """Refuse a ``--commands`` entry the client refuses (its thesis ranges): every point would be
    refused."""
    client = parse_command(text).dry_run(cfg)
    if client.last_error:
        raise ValueError(f"--commands {text!r}: the client refuses it ({client.last_error})")


def _micrometres_inside(v: float) -> float:
    """``v`` rounded to the micrometre, but never beyond it (a drawn deck length ending in 5 at the
    seventh digit would otherwise put a flush payload off the deck)."""
    r = round(v, 6)
    return round(r - 1e-6, 6) if r > v + 1e-9 else r


def with_payload(cfg: TwinConfig, mass_kg: float, xy_m: tuple[float, float]) -> TwinConfig:
    """``cfg`` with another payload, validated again (raises :class:`ConfigError`)."""
    return with_values(cfg, {"payload.mass_kg": mass_kg, "payload.xy_m": list(xy_m)})


@dataclass(frozen=True)
class Point:
    """One sweep point (picklable work item)."""

    mass_kg: float
    position: str
    command: str
    duration_s: float
    firmware: str
    cfg: TwinConfig
    rrd_path: str | None = (
        None  # write the point's Rerun recording here (not part of the fingerprint)
    )
    mcap_path: str | None = None  # write the point's ROS 2 topics here
    sample: int | None = None  # index of the drawn configuration ``cfg`` (None: the nominal one)
    sample_id: str = (
        ""  # hash of the sample's drawn values (amr_twin.calibration.draws.Draws.sample_id)
    )

    @property
    def key(self) -> str:
        key = f"m{self.mass_kg:g}kg_{self.position}_{self.command}".replace(":", "_").replace(
            "/", "_"
        )
        return key if self.sample is None else f"{key}_s{self.sample}_{self.sample_id}"

    @property
    def fingerprint(self) -> str:
        from amr_twin.controllers.firmware import (
            firmware_identity,
        )  # avr: the sketch's sources count too

        text = (
            self.cfg.model_dump_json()
            + f"|{firmware_identity(self.firmware)}|{self.duration_s}"
            + f"|rows {ROWS}"
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]
