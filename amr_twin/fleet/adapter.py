"""One vehicle's VDA 5050 2.0 side: orders and instant actions in, state and visualization out, on
the twin's clock.

:class:`VehicleAdapter` takes the messages of the ``order`` and ``instantActions`` topics
(:meth:`handle`, in the twin's thread) and, every ``TICK_S`` of simulated time, follows the order
(:class:`~amr_twin.fleet.route.Route`). A node with actions is stopped at; its actions run one after
the other once the vehicle stands (:class:`~amr_twin.fleet.handling.Handling`), then it drives on;
while charging it drives nowhere. The state goes out at every change and at least every
``STATE_PERIOD_S``; the visualization every tick. A refused order or action is answered with an
error in the state (:class:`~amr_twin.fleet.order.Rejection`), never an exception."""

from __future__ import annotations

import json

from amr_twin.fleet import state_message
from amr_twin.fleet.actions import (
    EDGE_ACTIONS,
    INSTANT_ACTIONS,
    NODE_ACTIONS,
    Action,
    ActionStates,
    parse_instant_actions,
)
from amr_twin.fleet.order import ORDER_ERRORS, Rejection
from amr_twin.fleet.order_message import order_header, parse_order
from amr_twin.fleet.route import Route
from amr_twin.fleet.vehicle import within

TICK_S = 0.1
STATE_PERIOD_S = 1.0
DRIVING_M_S, DRIVING_RAD_S = 0.01, 0.02
"""Below both the vehicle counts as standing (``driving`` false)."""


class VehicleAdapter:
    """``vehicle`` (:class:`~amr_twin.fleet.vehicle.Vehicle`) behind VDA 5050; ``send(subtopic,
    message)`` publishes, ``stamper`` (:class:`~amr_twin.fleet.protocol.Stamper`) heads each
    message, ``factsheet`` is the factsheet's body; ``xy_tolerance_m``: the vehicle's own tolerance
    at a node (allowedDeviationXY 0); ``handling``: its load and charging actions
    (:class:`~amr_twin.fleet.handling.Handling`)."""

    def __init__(
        self,
        vehicle,
        clock,
        send,
        stamper,
        factsheet: dict,
        xy_tolerance_m: float = 0.25,
        *,
        handling,
    ):
        self.vehicle, self.clock, self.send, self.stamper = vehicle, clock, send, stamper
        self.factsheet_body, self.xy_tolerance_m = factsheet, xy_tolerance_m
        self.handling = handling
        self.route = Route()
        self.actions = ActionStates()
        self.errors: list[dict] = []
        self.paused = False
        self._last_order_header: int | None = None
        self._changed, self._last_state_s, self._driving = True, -1e9, False
        self.log: list[tuple[float, str, dict]] = []
        """Every message sent: (t_s, subtopic, message)."""
        self._timer = clock.schedule_every(clock.now_us, int(TICK_S * 1e6), self._tick)

    # -- in ---------------------------------------------------------------------------------------
    def handle(self, subtopic: str, payload: bytes) -> None:
        """A message of ``order`` or ``instantActions`` (raw JSON); a bad one becomes an error in
        the state."""
        try:
            msg = json.loads(payload)
        except (ValueError, UnicodeDecodeError) as exc:
            self._error(
                Rejection(
                    "validationError", f"{subtopic}: not JSON ({exc})", (("topic", subtopic),)
                )
            )
            return
        if subtopic == "order":
            self._on_order(msg)
        elif subtopic == "instantActions":
            self._on_instant_actions(msg)
        self._changed = True

    def _error(self, rejection: Rejection) -> None:
        self.errors.append(rejection.error())
        self._changed = True

    def _on_order(self, msg) -> None:
        try:
            self._last_order_header = order_header(msg, self._last_order_header)
            order = parse_order(msg, self.vehicle.map_id, NODE_ACTIONS, EDGE_ACTIONS)
        except Rejection as exc:
            self._error(exc)
            return
        try:
            accepted = self.route.accept(
                order,
                self.actions,
                charging=self.handling.charging,
                pose=self.vehicle.pose(),
                xy_tolerance_m=self.xy_tolerance_m,
            )
        except Rejection as exc:
            self._error(exc)
            return
        if accepted:
            self.errors = [e for e in self.errors if e["errorType"] not in ORDER_ERRORS]

    def _on_instant_actions(self, msg) -> None:
        try:
            parsed = parse_instant_actions(msg)
        except Rejection as exc:
            self._error(exc)
            return
        for a in parsed:
            if isinstance(a, Rejection):
                self._error(a)
                continue
            self.actions.add(a.action_id, a.action_type, "INITIALIZING")
            if a.action_type not in INSTANT_ACTIONS:
                self.actions.set(a.action_id, "FAILED", "not an instant action of this vehicle")
                self._error(
                    Rejection(
                        "actionError",
                        f"instant action {a.action_type} is not one this vehicle performs",
                        (
                            ("topic", "instantActions"),
                            ("actionId", a.action_id),
                            ("actionType", a.action_type),
                        ),
                    )
                )
                continue
            getattr(self, f"_instant_{a.action_type}")(a.action_id, a.params)

    def _instant_cancelOrder(self, action_id: str, _params) -> None:
        route = self.route
        if not route.nodes and route.goal is None and not route.queue and not self.handling.busy:
            self.actions.set(action_id, "FAILED", "no order to cancel")
            self._error(
                Rejection(
                    "noOrderToCancel",
                    "cancelOrder: the vehicle has no order",
                    (("topic", "instantActions"), ("actionId", action_id)),
                )
            )
            return
        self.vehicle.cancel()
        route.clear()
        self.handling.abort()
        self.actions.fail_order_actions("order cancelled")
        self.actions.set(action_id, "RUNNING")

    def _instant_startPause(self, action_id: str, _params) -> None:
        if not self.paused and self.route.goal is not None:
            self.vehicle.cancel()
            self.route.goal = None
        self.paused = True
        self.actions.set(action_id, "RUNNING")

    def _instant_stopPause(self, action_id: str, _params) -> None:
        self.paused = False
        self.actions.set(action_id, "FINISHED")

    def _instant_initPosition(self, action_id: str, params: dict) -> None:
        x, y, theta = (params.get(k) for k in ("x", "y", "theta"))
        ok = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (x, y, theta))
        if (
            ok
            and params.get("mapId", self.vehicle.map_id) == self.vehicle.map_id
            and within(self.vehicle.pose(), x, y, theta, 2 * self.xy_tolerance_m, 0.35)
        ):
            node_id, seq = self.route.last_node
            self.route.last_node = (str(params.get("lastNodeId", node_id)), seq)
            self.actions.set(
                action_id, "FINISHED", "the pose agrees with the vehicle's localisation"
            )
            return
        self.actions.set(
            action_id,
            "FAILED",
            "the twin's pose cannot be overridden: x, y, theta (and mapId) must "
            "agree with its localisation",
        )
        self._error(
            Rejection(
                "actionError",
                "initPosition: the given pose is not where the vehicle is",
                (("topic", "instantActions"), ("actionId", action_id)),
            )
        )

    def _instant_stateRequest(self, action_id: str, _params) -> None:
        self.actions.set(action_id, "FINISHED")
        self._publish_state()

    def _instant_factsheetRequest(self, action_id: str, _params) -> None:
        self.publish_factsheet()
        self.actions.set(action_id, "FINISHED")

    def _instant_startCharging(self, action_id: str, _params) -> None:
        self._start(Action(action_id, "startCharging"))

    def _instant_stopCharging(self, action_id: str, _params) -> None:
        self._start(Action(action_id, "stopCharging"))

    # -- the vehicle's own actions ------------------------------------------------------------
    def _start(self, action: Action) -> None:
        try:
            status, result = self.handling.start(action, self.clock.now_s, not self._driving)
        except Rejection as exc:
            self.actions.set(action.action_id, "FAILED", exc.description)
            self._error(exc)
            return
        self.actions.set(action.action_id, status, result)

    def _do_actions(self) -> None:
        """Finish the running pick or drop when its time is up; start the next action of the node
        reached once the vehicle stands."""
        done = self.handling.step(self.clock.now_s)
        if done is not None:
            self.actions.set(done[0].action_id, "FINISHED", done[1])
        if not self.handling.busy and self.route.queue and not self._driving and not self.paused:
            self._start(self.route.queue.pop(0))

    # -- the order ----------------------------------------------------------------------------
    def _follow(self) -> None:
        route = self.route
        if route.queue or self.handling.busy:
            self._do_actions()
            return
        if self.paused or self.handling.charging or not route.nodes or not route.nodes[0].released:
            return
        traversed, error = route.drive(self.vehicle, self.xy_tolerance_m)
        if traversed:
            self._changed = True
        elif error is not None:
            self._error(error)

    def _tick(self) -> None:
        self._follow()
        v, w = self.vehicle.velocity()
        driving = abs(v) > DRIVING_M_S or abs(w) > DRIVING_RAD_S
        if driving != self._driving:
            self._driving, self._changed = driving, True
        if not driving:
            for kind in ("cancelOrder", "startPause"):
                for s in self.actions.running(kind):
                    self.actions.set(s.action_id, "FINISHED")
        self._publish_visualization()
        now = self.clock.now_s
        if (
            self._changed
            or self.actions.changed
            or now - self._last_state_s >= STATE_PERIOD_S - 1e-9
        ):
            self._publish_state()

    # -- out ----------------------------------------------------------------------------------
    def _emit(self, subtopic: str, body: dict) -> dict:
        t = self.clock.now_s
        msg = {**self.stamper.header(subtopic, t), **body}
        self.log.append((t, subtopic, msg))
        self.send(subtopic, msg)
        return msg

    def _publish_visualization(self) -> None:
        self._emit("visualization", state_message.visualization(self.vehicle))

    def _publish_state(self) -> None:
        body = state_message.state(
            self.vehicle,
            self.handling,
            self.route.order,
            self.route.last_node,
            self.route.nodes,
            self.route.edges,
            self.actions,
            self.errors,
            driving=self._driving,
            paused=self.paused,
        )
        self._emit("state", body)
        self._changed, self.actions.changed, self._last_state_s = False, False, self.clock.now_s

    def publish_factsheet(self) -> None:
        """Send the factsheet (at connection and on factsheetRequest)."""
        self._emit("factsheet", self.factsheet_body)

    def connection(self, state: str) -> dict:
        """A ``connection`` message with ``state`` (ONLINE, OFFLINE, CONNECTIONBROKEN), not sent
        (the transport sends it, or sets it as its last will)."""
        return {**self.stamper.header("connection", self.clock.now_s), "connectionState": state}

    def close(self) -> None:
        """Stop the adapter's timer."""
        self._timer.cancel()
