"""The action states of one vehicle (the specification's section 6.11): each action received, in
order, with its status WAITING, INITIALIZING, RUNNING, FINISHED or FAILED (the 2.0 schema has no
PAUSED); the actions of an ``instantActions`` message (:func:`parse_instant_actions`)."""

from __future__ import annotations

from dataclasses import dataclass

from amr_twin.fleet.order import Rejection

INSTANT_ACTIONS = frozenset(
    {
        "cancelOrder",
        "startPause",
        "stopPause",
        "initPosition",
        "stateRequest",
        "factsheetRequest",
        "startCharging",
        "stopCharging",
    }
)
"""The instant actions this vehicle performs."""
NODE_ACTIONS = frozenset({"pick", "drop", "startCharging", "stopCharging"})
"""The node actions it performs (:mod:`amr_twin.fleet.handling`)."""
EDGE_ACTIONS: frozenset = frozenset()
BLOCKING_TYPES = ("NONE", "SOFT", "HARD")
DONE = ("FINISHED", "FAILED")


@dataclass(frozen=True)
class Action:
    """An action of an order or an instant action: its id, type, ``blocking`` type (NONE, SOFT,
    HARD) and ``parameters`` ((key, value), ... as sent)."""

    action_id: str
    action_type: str
    blocking: str = "HARD"
    parameters: tuple = ()

    @property
    def params(self) -> dict:
        """The parameters by key."""
        return dict(self.parameters)


@dataclass
class ActionState:
    """One action's state; ``order``: it came with the order (False: an instant action)."""

    action_id: str
    action_type: str
    status: str = "WAITING"
    result: str | None = None
    order: bool = False

    def message(self) -> dict:
        """The state's ``actionStates`` entry."""
        out = {
            "actionId": self.action_id,
            "actionType": self.action_type,
            "actionStatus": self.status,
        }
        if self.result is not None:
            out["resultDescription"] = self.result
        return out


class ActionStates:
    """The actions of the present order and the instant actions since, by actionId (insertion
    order)."""

    def __init__(self):
        self._states: dict[str, ActionState] = {}
        self.changed = False

    def add(
        self, action_id: str, action_type: str, status: str = "WAITING", order: bool = False
    ) -> ActionState:
        state = self._states[action_id] = ActionState(action_id, action_type, status, order=order)
        self.changed = True
        return state

    def set(self, action_id: str, status: str, result: str | None = None) -> None:
        state = self._states[action_id]
        if (state.status, state.result) != (status, result if result is not None else state.result):
            state.status, self.changed = status, True
            if result is not None:
                state.result = result

    def get(self, action_id: str) -> ActionState | None:
        return self._states.get(action_id)

    def running(self, action_type: str) -> list[ActionState]:
        """The actions of ``action_type`` not yet finished or failed."""
        return [
            s
            for s in self._states.values()
            if s.action_type == action_type and s.status not in DONE
        ]

    def fail_order_actions(self, reason: str) -> None:
        """Every order action not finished fails (a cancelled order)."""
        for s in self._states.values():
            if s.order and s.status not in DONE:
                self.set(s.action_id, "FAILED", reason)

    def new_order(self) -> None:
        """A new order was accepted: the states kept until now are dropped (section 6.10.6)."""
        self._states = {k: s for k, s in self._states.items() if s.status not in DONE}
        self.changed = True

    def messages(self) -> list[dict]:
        return [s.message() for s in self._states.values()]


def parse_instant_actions(msg) -> list:
    """The actions of an ``instantActions`` message in order: an :class:`Action` each, or a
    :class:`~amr_twin.fleet.order.Rejection` for one without actionId or actionType; raises it when
    the message has no ``actions`` array (``instantActions``, 1.1's name, read too)."""
    actions = msg.get("actions", msg.get("instantActions")) if isinstance(msg, dict) else None
    refs = (("topic", "instantActions"),)
    if not isinstance(actions, list):
        raise Rejection(
            "validationError", "instantActions: field actions missing or not an array", refs
        )
    out: list = []
    for a in actions:
        kind = a.get("actionType", a.get("actionName")) if isinstance(a, dict) else None
        action_id = a.get("actionId") if isinstance(a, dict) else None
        if not isinstance(kind, str) or not isinstance(action_id, str):
            out.append(
                Rejection(
                    "validationError",
                    "instantActions: an action without actionId or actionType",
                    refs,
                )
            )
            continue
        params = a.get("actionParameters") or []
        pairs = tuple((p.get("key"), p.get("value")) for p in params if isinstance(p, dict))
        out.append(Action(action_id, kind, parameters=pairs))
    return out
