"""One wheel_Command_Client call, as in the terminal menu of fig. 3.2: what a run or mission sends.

>>> from amr_twin.assembly.command import Command
>>> Command.parse("angular:30:0.5").describe()
{'kind': 'angular', 'speed_deg_s': 30.0, 'icc_m': 0.5}
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from amr_twin.model.config import TwinConfig

if TYPE_CHECKING:
    from amr_twin.assembly.twin import Twin

KINDS = ("linear", "angular", "motor", "stop")


@dataclass(frozen=True)
class Command:
    """One wheel_Command_Client call, as in the terminal menu of fig. 3.2.

    kind : "linear" (speed_m_s, negative = backward), "angular" (speed_deg_s,
        icc_m; REP-103: ICC positive to the left), "motor" (wheel, direction,
        speed_m_s) or "stop".
    """

    kind: str
    speed_m_s: float = 0.0
    speed_deg_s: float = 0.0
    icc_m: float = 0.0
    wheel: str = "left"
    direction: str = "forward"

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"command kind: {self.kind!r} is not one of {', '.join(KINDS)}")
        for name in ("speed_m_s", "speed_deg_s", "icc_m"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"{name}: {value} must be a finite number")
        if self.wheel not in ("left", "right"):
            raise ValueError(f"wheel: {self.wheel!r} must be left or right")
        if self.direction not in ("forward", "backward"):
            raise ValueError(f"direction: {self.direction!r} must be forward or backward")

    @classmethod
    def parse(cls, text: str, what: str = "command") -> "Command":
        """``linear:V``, ``angular:DEG_S:ICC_M``, ``motor:WHEEL:V`` (signed), ``motor:WHEEL:DIR:V``
        or ``stop``.

        The form used by ``amr-twin sweep --commands`` and the ``command`` column of a
        calibration log (m/s, deg/s, m). ``what`` names the input in the error message.
        """
        parts = text.strip().split(":")
        try:
            if parts[0] == "linear" and len(parts) == 2:
                return cls("linear", speed_m_s=float(parts[1]))
            if parts[0] == "angular" and len(parts) == 3:
                return cls("angular", speed_deg_s=float(parts[1]), icc_m=float(parts[2]))
            if parts[0] == "motor" and len(parts) == 3:
                v = float(parts[2])
                return cls(
                    "motor",
                    wheel=parts[1],
                    direction="forward" if v >= 0 else "backward",
                    speed_m_s=abs(v),
                )
            if parts[0] == "motor" and len(parts) == 4:
                return cls("motor", wheel=parts[1], direction=parts[2], speed_m_s=float(parts[3]))
            if parts[0] == "stop" and len(parts) == 1:
                return cls("stop")
        except ValueError as exc:
            raise ValueError(f"{what} {text!r}: {exc}") from None
        raise ValueError(
            f"{what} {text!r}: expected linear:V, angular:DEG_S:ICC_M, motor:WHEEL:V, "
            "motor:WHEEL:DIR:V or stop"
        )

    def send(self, twin: Twin) -> int:
        """Call the client as the menu would; return its code (0 ok, 1 value error, -1 failed)."""
        client = twin.client
        if self.kind == "linear":
            return client.linear(self.speed_m_s)
        if self.kind == "angular":
            return client.angular(self.speed_deg_s, self.icc_m)
        if self.kind == "motor":
            return client.motor(self.wheel, self.direction, self.speed_m_s)
        return client.stop()

    def dry_run(self, cfg: TwinConfig):
        """Send the command to a client of its own, with no twin (its conversions and range checks
        only): the client after the call (``last_request``, ``last_error``)."""
        from amr_twin.controllers.wheel_command import WheelCommandClient, WheelCommandService
        from amr_twin.ros.bus import Bus
        from amr_twin.base.clock import VirtualClock

        bus = Bus(VirtualClock())
        WheelCommandService(bus)
        client = WheelCommandClient(
            bus, wheel_radius_m=cfg.wheel.radius_m, half_separation_m=cfg.wheel.separation_m / 2
        )
        self.send(type("Twinless", (), {"client": client})())
        return client

    def describe(self) -> dict:
        """The command as a JSON-ready dict."""
        out = {"kind": self.kind}
        if self.kind == "linear":
            out["speed_m_s"] = self.speed_m_s
        elif self.kind == "angular":
            out.update(speed_deg_s=self.speed_deg_s, icc_m=self.icc_m)
        elif self.kind == "motor":
            out.update(wheel=self.wheel, direction=self.direction, speed_m_s=self.speed_m_s)
        return out
