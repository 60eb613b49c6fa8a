"""The vehicle's own actions (VDA 5050 2.0's predefined ``pick``, ``drop``, ``startCharging`` and
``stopCharging``, section 6.8.2): a load put on the deck or taken off it, the physics carrying its
mass; the charger connected at a charging station of the world.

:class:`Handling` runs one action at a time (HARD blocking: the vehicle stands): ``pick`` and
``drop`` are RUNNING for ``payload.handling_time_s`` (a worker lifts the box: the robot has no load
handling device), then FINISHED with the load's mass given to (or taken from) the physics; the
charging actions finish at once. An action that cannot be done FAILED with an ``actionError`` in
the state: a pick without a ``weight`` (kg) or over the deck's ``payload.max_mass_kg``, a second
load, a drop with no load or of another ``loadId``, charging away from a station or while driving.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from amr_twin.fleet.actions import Action
from amr_twin.fleet.order import Rejection
from amr_twin.fleet.vehicle import within


@dataclass(frozen=True)
class Load:
    """The load on the deck: ``weight_kg`` and, as the pick named them, its id and type."""

    weight_kg: float
    load_id: str | None = None
    load_type: str | None = None

    def message(self) -> dict:
        """The state's ``loads`` entry."""
        out: dict = {"weight": self.weight_kg}
        if self.load_id is not None:
            out["loadId"] = self.load_id
        if self.load_type is not None:
            out["loadType"] = self.load_type
        return out


class Handling:
    """The load and charging actions of ``vehicle`` (:class:`~amr_twin.fleet.vehicle.Vehicle`):
    ``max_load_kg``, ``handling_time_s`` (s a pick or drop takes), ``stations``
    (:class:`~amr_twin.model.worlds.ChargingStation`) and how near one the vehicle must stand
    (``xy_tolerance_m``, ``yaw_tolerance_rad``); ``load``: what it carries at the start. The
    adapter keeps the actions' states: :meth:`start` says how an action began, :meth:`step` which
    one ended."""

    def __init__(
        self,
        vehicle,
        max_load_kg: float,
        handling_time_s: float,
        stations: tuple = (),
        xy_tolerance_m: float = 0.25,
        yaw_tolerance_rad: float = 0.35,
        load: Load | None = None,
    ):
        self.vehicle, self.max_load_kg, self.handling_time_s = vehicle, max_load_kg, handling_time_s
        self.stations, self.tolerances = tuple(stations), (xy_tolerance_m, yaw_tolerance_rad)
        self.load = load
        self.charging = False
        self._running: tuple[Action, float, Load | None] | None = None

    @property
    def busy(self) -> bool:
        """Whether a pick or a drop is running."""
        return self._running is not None

    def loads(self) -> list[dict]:
        """The state's ``loads``."""
        return [self.load.message()] if self.load is not None else []

    def station(self):
        """The charging station the vehicle stands at (within the tolerances), or None."""
        pose = self.vehicle.pose()
        for s in self.stations:
            if within(pose, s.x_m, s.y_m, s.yaw_rad, *self.tolerances):
                return s
        return None

    def start(self, action: Action, now_s: float, standing: bool) -> tuple[str, str | None]:
        """Begin ``action``: its status now (RUNNING, or FINISHED for the charging actions) and
        result description; raises :class:`~amr_twin.fleet.order.Rejection` (an ``actionError``)
        when it cannot be done. ``standing``: the vehicle does not move."""
        if not standing and action.action_type != "stopCharging":
            raise self._refusal(action, "the vehicle is moving: it must stand")
        return getattr(self, f"_start_{action.action_type}")(action, now_s)

    def step(self, now_s: float) -> tuple[Action, str] | None:
        """The pick or drop whose time is up, with its result description (the physics carries
        the new load from now on); None while it runs or when none does."""
        if self._running is None or now_s < self._running[1] - 1e-9:
            return None
        action, _t, load = self._running
        self._running, self.load = None, load
        self.vehicle.set_payload_kg(0.0 if load is None else load.weight_kg)
        return action, "load on the deck" if load is not None else "deck empty"

    def abort(self) -> Action | None:
        """Stop the running pick or drop (a cancelled order), the load as it was; the action."""
        running, self._running = self._running, None
        return None if running is None else running[0]

    # -- the actions ------------------------------------------------------------------------
    def _refusal(self, action: Action, why: str) -> Rejection:
        return Rejection(
            "actionError",
            f"{action.action_type} {action.action_id}: {why}",
            (("actionId", action.action_id), ("actionType", action.action_type)),
        )

    def _start_pick(self, action: Action, now_s: float):
        p = action.params
        weight = p.get("weight")
        if isinstance(weight, bool) or not isinstance(weight, (int, float)):
            raise self._refusal(action, "parameter weight (kg, a number > 0) is required")
        if not (math.isfinite(weight) and 0 < weight <= self.max_load_kg):
            raise self._refusal(
                action,
                f"weight {weight} kg: must be > 0 and at most the {self.max_load_kg:g} kg the "
                "deck carries (factsheet maxLoadMass)",
            )
        if self.load is not None:
            raise self._refusal(action, "the deck already carries a load (one load position)")
        names = [p.get(k) for k in ("loadId", "loadType")]
        load = Load(float(weight), *(None if v is None else str(v) for v in names))
        self._running = (action, now_s + self.handling_time_s, load)
        return "RUNNING", None

    def _start_drop(self, action: Action, now_s: float):
        if self.load is None:
            raise self._refusal(action, "no load on the deck")
        load_id = action.params.get("loadId")
        if load_id is not None and self.load.load_id is not None and load_id != self.load.load_id:
            raise self._refusal(action, f"loadId {load_id!r} is not the load carried")
        self._running = (action, now_s + self.handling_time_s, None)
        return "RUNNING", None

    def _start_startCharging(self, action: Action, _now_s: float):
        station = self.station()
        if station is None:
            raise self._refusal(action, "not at a charging station")
        self.charging = True
        self.vehicle.set_charging(True)
        return "FINISHED", f"charging at {station.name}"

    def _start_stopCharging(self, action: Action, _now_s: float):
        was, self.charging = self.charging, False
        self.vehicle.set_charging(False)
        return "FINISHED", "charging stopped" if was else "not charging"
