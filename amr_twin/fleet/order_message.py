"""An ``order`` message read into an :class:`~amr_twin.fleet.order.Order` (the specification's
section 6.6).

:func:`parse_order` raises :class:`~amr_twin.fleet.order.Rejection` with the error the state
reports: ``validationError`` for a malformed order (a missing field, edges that do not join the
nodes in sequence, sequence ids out of step, a released element after an unreleased one),
``orderError`` for one this vehicle cannot carry out (no node position, another map, a trajectory,
an action it does not have)."""

from __future__ import annotations

import math

from amr_twin.fleet.actions import BLOCKING_TYPES, Action
from amr_twin.fleet.order import Edge, Node, Order, Rejection


def _get(msg: dict, key: str, kind, where: str, refs: tuple):
    value = msg.get(key)
    ok = (
        isinstance(value, kind) and not isinstance(value, bool)
        if kind in (int, float, (int, float))
        else isinstance(value, kind)
    )
    if not ok:
        raise Rejection(
            "validationError",
            f"{where}: field {key} missing or not a {getattr(kind, '__name__', 'number')}",
            refs,
        )
    if isinstance(value, float) and not math.isfinite(value):
        raise Rejection("validationError", f"{where}: field {key} is not finite", refs)
    return value


def _actions(owner: dict, where: str, refs: tuple, supported: frozenset) -> tuple:
    """The actions (:class:`~amr_twin.fleet.actions.Action`) of a node or an edge."""
    actions = owner.get("actions")
    if not isinstance(actions, list):
        raise Rejection("validationError", f"{where}: field actions missing or not an array", refs)
    out = []
    for a in actions:
        if (
            not isinstance(a, dict)
            or not isinstance(a.get("actionId"), str)
            or not isinstance(a.get("actionType"), str)
        ):
            raise Rejection(
                "validationError", f"{where}: an action without actionId or actionType", refs
            )
        here = refs + (("actionId", a["actionId"]), ("actionType", a["actionType"]))
        if a["actionType"] not in supported:
            raise Rejection(
                "orderError",
                f"{where}: action {a['actionType']} is not one this vehicle performs",
                here,
            )
        blocking = a.get("blockingType", "HARD")
        params = a.get("actionParameters") or []
        if blocking not in BLOCKING_TYPES or not isinstance(params, list):
            raise Rejection(
                "validationError",
                f"{where}: action {a['actionId']}: blockingType must be one of "
                f"{', '.join(BLOCKING_TYPES)} and actionParameters an array",
                here,
            )
        pairs = tuple(
            (p.get("key"), p.get("value"))
            for p in params
            if isinstance(p, dict) and isinstance(p.get("key"), str)
        )
        out.append(Action(a["actionId"], a["actionType"], blocking, pairs))
    return tuple(out)


def _node(n, i: int, map_id: str, refs: tuple, supported: frozenset) -> Node:
    if not isinstance(n, dict):
        raise Rejection("validationError", f"nodes[{i}] is not an object", refs)
    node_id = _get(n, "nodeId", str, f"nodes[{i}]", refs)
    refs = refs + (("nodeId", node_id),)
    seq = _get(n, "sequenceId", int, f"node {node_id}", refs)
    released = _get(n, "released", bool, f"node {node_id}", refs)
    actions = _actions(n, f"node {node_id}", refs, supported)
    pos = n.get("nodePosition")
    if not isinstance(pos, dict):
        raise Rejection(
            "orderError",
            f"node {node_id}: no nodePosition (this vehicle plans its own way to a position)",
            refs,
        )
    x = _get(pos, "x", (int, float), f"node {node_id}", refs)
    y = _get(pos, "y", (int, float), f"node {node_id}", refs)
    node_map = _get(pos, "mapId", str, f"node {node_id}", refs)
    if node_map != map_id:
        raise Rejection(
            "orderError",
            f"node {node_id}: mapId {node_map!r} is not this vehicle's map {map_id!r}",
            refs + (("mapId", node_map),),
        )
    theta = pos.get("theta")
    if theta is not None:
        theta = _get(pos, "theta", (int, float), f"node {node_id}", refs)
        if abs(theta) > math.pi + 1e-9:
            raise Rejection(
                "validationError", f"node {node_id}: theta {theta} is outside [-pi, pi]", refs
            )
    # The 2.0.0 schema spells allowedDeviationXy; the text (and 1.1) allowedDeviationXY: both read.
    dev = [
        pos.get("allowedDeviationXy", pos.get("allowedDeviationXY", 0.0)),
        pos.get("allowedDeviationTheta", 0.0),
    ]
    if not all(
        isinstance(d, (int, float)) and not isinstance(d, bool) and math.isfinite(d) and d >= 0
        for d in dev
    ):
        raise Rejection(
            "validationError", f"node {node_id}: allowed deviations must be numbers >= 0", refs
        )
    return Node(
        node_id,
        seq,
        released,
        float(x),
        float(y),
        None if theta is None else float(theta),
        node_map,
        float(dev[0]),
        float(dev[1]),
        n.get("nodeDescription"),
        actions,
    )


def _edge(e, i: int, refs: tuple, supported: frozenset) -> Edge:
    if not isinstance(e, dict):
        raise Rejection("validationError", f"edges[{i}] is not an object", refs)
    edge_id = _get(e, "edgeId", str, f"edges[{i}]", refs)
    refs = refs + (("edgeId", edge_id),)
    where = f"edge {edge_id}"
    seq = _get(e, "sequenceId", int, where, refs)
    released = _get(e, "released", bool, where, refs)
    start, end = _get(e, "startNodeId", str, where, refs), _get(e, "endNodeId", str, where, refs)
    _actions(e, where, refs, supported)
    if e.get("trajectory") is not None:
        raise Rejection(
            "orderError",
            f"{where}: a trajectory (this vehicle plans its own path)",
            refs + (("trajectory", "edge"),),
        )
    speed = e.get("maxSpeed")
    if speed is not None and not (
        isinstance(speed, (int, float)) and math.isfinite(speed) and speed > 0
    ):
        raise Rejection("validationError", f"{where}: maxSpeed must be a number > 0", refs)
    return Edge(
        edge_id,
        seq,
        released,
        start,
        end,
        None if speed is None else float(speed),
        e.get("edgeDescription"),
    )


def parse_order(
    msg: dict,
    map_id: str,
    node_actions: frozenset = frozenset(),
    edge_actions: frozenset = frozenset(),
) -> Order:
    """The :class:`Order` of an ``order`` message for a vehicle on ``map_id`` that performs
    ``node_actions`` and ``edge_actions``; raises :class:`Rejection` (module docstring)."""
    if not isinstance(msg, dict):
        raise Rejection("validationError", "the order is not a JSON object", (("topic", "order"),))
    refs: tuple = (("topic", "order"),)
    if isinstance(msg.get("headerId"), int):
        refs += (("headerId", msg["headerId"]),)
    header_id = _get(msg, "headerId", int, "order", refs)
    order_id = _get(msg, "orderId", str, "order", refs)
    refs += (("orderId", order_id),)
    update_id = _get(msg, "orderUpdateId", int, "order", refs)
    refs += (("orderUpdateId", update_id),)
    nodes, edges = msg.get("nodes"), msg.get("edges")
    if not isinstance(nodes, list) or not nodes or not isinstance(edges, list):
        raise Rejection(
            "validationError", "order: nodes must be a non-empty array and edges an array", refs
        )
    if len(edges) != len(nodes) - 1:
        raise Rejection(
            "validationError",
            f"order: {len(edges)} edges for {len(nodes)} nodes (one fewer is needed)",
            refs,
        )
    nodes = [_node(n, i, map_id, refs, node_actions) for i, n in enumerate(nodes)]
    edges = [_edge(e, i, refs, edge_actions) for i, e in enumerate(edges)]
    seq0 = nodes[0].sequence_id
    for i, n in enumerate(nodes):
        if n.sequence_id != seq0 + 2 * i:
            raise Rejection(
                "validationError",
                f"node {n.node_id}: sequenceId {n.sequence_id}, expected {seq0 + 2 * i}",
                refs + (("nodeId", n.node_id), ("sequenceId", n.sequence_id)),
            )
    for i, e in enumerate(edges):
        a, b = nodes[i], nodes[i + 1]
        if e.sequence_id != seq0 + 2 * i + 1:
            raise Rejection(
                "validationError",
                f"edge {e.edge_id}: sequenceId {e.sequence_id}, expected {seq0 + 2 * i + 1}",
                refs + (("edgeId", e.edge_id), ("sequenceId", e.sequence_id)),
            )
        for key, given, want in (
            ("startNodeId", e.start_node_id, a.node_id),
            ("endNodeId", e.end_node_id, b.node_id),
        ):
            if given != want:
                raise Rejection(
                    "validationError",
                    f"edge {e.edge_id}: {key} {given!r} is not the node beside it in "
                    f"the order ({want!r})",
                    refs + (("edgeId", e.edge_id), (key, given)),
                )
        if e.released and not (a.released and b.released):
            raise Rejection(
                "validationError",
                f"edge {e.edge_id}: released between nodes not both released",
                refs + (("edgeId", e.edge_id),),
            )
    sequence = [x for pair in zip(nodes, edges + [None]) for x in pair if x is not None]
    released = [x.released for x in sequence]
    if not released[0]:
        raise Rejection("validationError", "order: the first node is not released", refs)
    if False in released and any(released[released.index(False) :]):
        raise Rejection(
            "validationError", "order: a released node or edge after an unreleased one", refs
        )
    return Order(order_id, update_id, header_id, nodes, edges)


def order_header(msg, last_header: int | None) -> int | None:
    """The ``headerId`` to remember after an ``order`` message (``last_header`` when it has none);
    raises :class:`~amr_twin.fleet.order.Rejection` for one not after ``last_header`` (a late or
    repeated message)."""
    header = msg.get("headerId") if isinstance(msg, dict) else None
    if isinstance(header, int) and last_header is not None and 0 < header <= last_header:
        raise Rejection(
            "validationError",
            f"order: headerId {header} is not after the last order's "
            f"{last_header} (a late or repeated message)",
            (("topic", "order"), ("headerId", header)),
        )
    return header if isinstance(header, int) else last_header
