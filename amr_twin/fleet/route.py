"""The order one VDA 5050 vehicle drives: :class:`Route` keeps the nodes and edges left, the last
node traversed, the goal sent to the vehicle and the actions of the node reached still to start
(the specification's sections 6.6 and 6.7).

The next released node is sent to the vehicle as a goal (with its theta, if any); a node counts as
traversed when the goal succeeds or, for a node the vehicle drives on from, when it passes within
the node's allowed deviation (the vehicle's goal tolerance when 0). It stops at the last released
node; unreleased ones (the horizon) wait for an order update, which is stitched at the last base
node (:func:`~amr_twin.fleet.order.stitch`)."""

from __future__ import annotations

from amr_twin.fleet.actions import Action, ActionStates
from amr_twin.fleet.order import Order, Rejection, admit
from amr_twin.fleet.vehicle import within


class Route:
    """The order being driven (None: none yet); ``nodes`` and ``edges`` left in sequence,
    ``last_node`` (nodeId, sequenceId) traversed, ``goal`` (node, outcome) sent to the vehicle,
    ``queue``: the actions of the node reached, still to start."""

    def __init__(self):
        self.order: Order | None = None
        self.nodes: list = []
        self.edges: list = []
        self.last_node = ("", 0)
        self._last_node_obj = None
        self.goal = None
        self.queue: list[Action] = []

    def last_base(self):
        """The last released node of the order: still to drive, or the last one traversed."""
        released = [n for n in self.nodes if n.released]
        return released[-1] if released else self._last_node_obj

    def accept(
        self, order: Order, actions: ActionStates, *, charging: bool, pose, xy_tolerance_m: float
    ) -> bool:
        """Take on ``order`` (:func:`~amr_twin.fleet.order.admit`), its released node actions
        added to ``actions`` as WAITING; False: the same message again, ignored. Raises
        :class:`~amr_twin.fleet.order.Rejection`."""
        current = self.order
        admitted = admit(
            order,
            current,
            self.nodes,
            self.edges,
            self.last_base(),
            charging=charging,
            pose=pose,
            xy_tolerance_m=xy_tolerance_m,
        )
        if admitted is None:
            return False
        self.nodes, self.edges, stitched = admitted
        if current is None or order.order_id != current.order_id:
            actions.new_order()
        for a in (a for n in self.nodes if n.released for a in n.actions):
            if actions.get(a.action_id) is None:
                actions.add(a.action_id, a.action_type, "WAITING", order=True)
        self.order = order
        if not stitched:  # the first node is where the vehicle stands: traversed now
            self.traverse(self.nodes[0], first=True)
        elif self.goal is not None and self.goal[0] not in self.nodes:
            self.goal = None
        return True

    def traverse(self, node, first: bool = False) -> None:
        """``node`` reached (``first``: the order's first, with no edge before it)."""
        self.nodes.remove(node)
        if not first and self.edges:
            self.edges.pop(0)
        self.last_node, self._last_node_obj = (node.node_id, node.sequence_id), node
        self.queue.extend(node.actions)
        self.goal = None

    def clear(self) -> None:
        """Nothing left to drive or do (the order cancelled or failed)."""
        self.nodes, self.edges, self.goal, self.queue = [], [], None, []

    def drive(self, vehicle, xy_tolerance_m: float) -> tuple[bool, Rejection | None]:
        """Send ``vehicle`` to the next released node (once) and see how it fares: (traversed,
        None), or (False, the ``navigationError``) when the vehicle gave up, everything left
        cleared. ``xy_tolerance_m``: the vehicle's own tolerance at a node (m)."""
        node = self.nodes[0]
        if self.goal is None or self.goal[0] is not node:
            self.goal = (node, vehicle.send_goal(node.x_m, node.y_m, node.theta_rad))
        outcome = self.goal[1]
        drives_on = len(self.nodes) > 1 and self.nodes[1].released and not node.actions
        tol = max(node.deviation_xy_m, xy_tolerance_m)
        if outcome.status == "succeeded" or (
            drives_on
            and within(
                vehicle.pose(), node.x_m, node.y_m, node.theta_rad, tol, node.deviation_theta_rad
            )
        ):
            self.traverse(node)
            return True, None
        if outcome.status == "aborted":
            error = Rejection(
                "navigationError",
                f"node {node.node_id} not reached: {outcome.reason}",
                (
                    ("orderId", self.order.order_id),
                    ("orderUpdateId", self.order.update_id),
                    ("nodeId", node.node_id),
                    ("sequenceId", node.sequence_id),
                ),
            )
            self.nodes, self.edges, self.goal = [], [], None
            return False, error
        return False, None
