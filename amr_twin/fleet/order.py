"""VDA 5050 2.0 orders (the specification's sections 6.6 and 6.7): their nodes and edges, the
:class:`Rejection` of one refused, :func:`admit` (whether an order or update is taken on) and
:func:`stitch` (an order update appended to the order being driven, section 6.6.2). Messages are
read into an :class:`Order` by :func:`~amr_twin.fleet.order_message.parse_order`."""

from __future__ import annotations

from dataclasses import dataclass, field

from amr_twin.fleet.vehicle import within


class Rejection(Exception):
    """An order or action refused: ``error_type``, a one-line description, ``references`` ((key,
    value), ...)."""

    def __init__(self, error_type: str, description: str, references: tuple = ()):
        super().__init__(description)
        self.error_type, self.description, self.references = (
            error_type,
            description,
            tuple(references),
        )

    def error(self) -> dict:
        """The state's ``errors`` entry (level WARNING: the vehicle stays ready for a new order)."""
        return {
            "errorType": self.error_type,
            "errorLevel": "WARNING",
            "errorDescription": self.description,
            "errorReferences": [
                {"referenceKey": k, "referenceValue": str(v)} for k, v in self.references
            ],
        }


ORDER_ERRORS = (
    "validationError",
    "orderError",
    "orderUpdateError",
    "noRouteError",
    "navigationError",
    "actionError",
)
"""The state's error types an accepted order clears."""


@dataclass(frozen=True)
class Node:
    """One node: position on ``map_id`` (m, rad; theta None: any heading), allowed deviations (m,
    rad; 0: the vehicle's own tolerance), whether released (base) or not (horizon)."""

    node_id: str
    sequence_id: int
    released: bool
    x_m: float
    y_m: float
    theta_rad: float | None
    map_id: str
    deviation_xy_m: float = 0.0
    deviation_theta_rad: float = 0.0
    description: str | None = None
    actions: tuple = ()
    """Its actions (:class:`~amr_twin.fleet.actions.Action`), in order."""

    def state(self) -> dict:
        """The state's ``nodeStates`` entry (its position only with a theta: the schema requires
        one)."""
        out = {"nodeId": self.node_id, "sequenceId": self.sequence_id, "released": self.released}
        if self.description is not None:
            out["nodeDescription"] = self.description
        if self.theta_rad is not None:
            out["nodePosition"] = {
                "x": self.x_m,
                "y": self.y_m,
                "theta": self.theta_rad,
                "mapId": self.map_id,
            }
        return out


@dataclass(frozen=True)
class Edge:
    """One edge from ``start_node_id`` to ``end_node_id``; ``max_speed_m_s`` None: the vehicle's own
    limit."""

    edge_id: str
    sequence_id: int
    released: bool
    start_node_id: str
    end_node_id: str
    max_speed_m_s: float | None = None
    description: str | None = None

    def state(self) -> dict:
        """The state's ``edgeStates`` entry."""
        out = {"edgeId": self.edge_id, "sequenceId": self.sequence_id, "released": self.released}
        if self.description is not None:
            out["edgeDescription"] = self.description
        return out


@dataclass
class Order:
    """An accepted order: its ids, the ``headerId`` of its last message, its nodes and edges in
    sequence."""

    order_id: str
    update_id: int
    header_id: int
    nodes: list = field(default_factory=list)
    edges: list = field(default_factory=list)


def stitch(
    remaining_nodes: list, remaining_edges: list, last_base: Node, update: Order
) -> tuple[list, list]:
    """The nodes and edges left to drive after ``update`` (an order update, or a new order
    continuing this one) is stitched onto the base: ``update``'s first node must be ``last_base``
    (nodeId and sequenceId), whose own actions and position stay; what followed it before (the old
    horizon) is replaced. Raises :class:`Rejection` (``orderUpdateError``)."""
    first = update.nodes[0]
    if (first.node_id, first.sequence_id) != (last_base.node_id, last_base.sequence_id):
        raise Rejection(
            "orderUpdateError",
            f"order update: its first node {first.node_id} "
            f"(sequenceId {first.sequence_id}) is not the last base node {last_base.node_id} "
            f"(sequenceId {last_base.sequence_id})",
            (
                ("topic", "order"),
                ("orderId", update.order_id),
                ("orderUpdateId", update.update_id),
                ("nodeId", first.node_id),
            ),
        )
    keep = [n for n in remaining_nodes if n.released and n.sequence_id < last_base.sequence_id]
    keep_edges = [
        e for e in remaining_edges if e.released and e.sequence_id < last_base.sequence_id
    ]
    head = [n for n in remaining_nodes if n.sequence_id == last_base.sequence_id]
    return keep + head + update.nodes[1:], keep_edges + update.edges


def admit(
    order: Order,
    current: Order | None,
    remaining_nodes: list,
    remaining_edges: list,
    last_base: Node | None,
    *,
    charging: bool,
    pose,
    xy_tolerance_m: float,
) -> tuple[list, list, bool] | None:
    """Whether a vehicle driving ``current`` (None: none yet) with ``remaining_nodes`` and
    ``remaining_edges`` left takes on ``order``: None for the same message again (ignored, section
    6.6.4.3), else (nodes, edges, stitched) to drive; stitched False: a new order whose first node
    is where the vehicle stands (``pose``, within the node's deviation or ``xy_tolerance_m``, m).
    ``last_base``: the node an update stitches at. Raises :class:`Rejection`."""
    released = [n for n in order.nodes if n.released]
    if (
        charging
        and len(released) > 1
        and "stopCharging" not in {a.action_type for a in order.nodes[0].actions}
    ):
        raise Rejection(
            "orderError",
            f"order {order.order_id}: the vehicle is charging and drives nowhere: "
            "stopCharging first (an instant action, or on the order's first node)",
            (("topic", "order"), ("orderId", order.order_id)),
        )
    if current is not None and order.order_id == current.order_id:
        if order.update_id < current.update_id:
            raise Rejection(
                "orderUpdateError",
                f"order {order.order_id}: orderUpdateId {order.update_id} is "
                f"lower than the present {current.update_id}",
                (
                    ("topic", "order"),
                    ("orderId", order.order_id),
                    ("orderUpdateId", order.update_id),
                ),
            )
        if order.update_id == current.update_id:
            return None
    if current is not None and (bool(remaining_nodes) or order.order_id == current.order_id):
        return (*stitch(remaining_nodes, remaining_edges, last_base, order), True)
    first = order.nodes[0]
    if not within(pose, first.x_m, first.y_m, None, max(first.deviation_xy_m, xy_tolerance_m), 0.0):
        raise Rejection(
            "noRouteError",
            f"order {order.order_id}: the first node {first.node_id} is not where "
            "the vehicle stands (nor within its allowed deviation)",
            (
                ("topic", "order"),
                ("orderId", order.order_id),
                ("orderUpdateId", order.update_id),
                ("nodeId", first.node_id),
            ),
        )
    return list(order.nodes), list(order.edges), False
