"""Traffic control by node reservation on a roadmap: which part of its route each vehicle may drive.

Rules (a vehicle's route is a list of node ids; it holds the nodes from the last one it passed to
the last one released to it):

- A node is held by at most one vehicle: no two vehicles on one node.
- The roadmap's *corridors* are its chains of two-way edges between key nodes (junctions, ends:
  nodes with other than two edges). A vehicle is released into a corridor only with every node of
  its way through it, to where its route leaves the corridor or ends, reserved at once. Two
  vehicles thus never drive one edge, nor meet head-on in a corridor (both would hold its nodes),
  and no vehicle stops inside a corridor waiting for one coming the other way.
- On a directed roadmap (:mod:`~amr_twin.fleet_manager.lanes`) one-way edges are reserved node by
  node, :data:`LOOKAHEAD_NODES` ahead: vehicles follow each other; a junction only with the node
  after it.
- A vehicle bound into a dead end (a dock) is released up to its mouth only with its way in: it
  does not stand in the mouth while another comes out.
- Nodes behind a vehicle are freed as it passes the next ones (``lastNodeId``).
- A vehicle refused is *waiting* for the holders of the nodes it needs; a cycle of vehicles waiting
  for each other is a deadlock (:meth:`Traffic.deadlock`, networkx' ``find_cycle``), for the
  manager to break by rerouting one of them or to report.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import networkx as nx


LOOKAHEAD_NODES = 3
"""On a directed roadmap, the nodes a vehicle holds ahead of the last one it passed (whole corridor
runs and junction crossings may hold more): a manager setting, about 7 m at the roadmap's 2.7 m
spacing, enough for an update to arrive before the vehicle slows for its last released node."""


@dataclass
class Plan:
    """One vehicle's route; ``passed``: index of the last node passed; ``held``: index of the last
    node released to it (it holds ``route[passed..held]``)."""

    route: list[str]
    passed: int = 0
    held: int = 0

    @property
    def done(self) -> bool:
        return self.passed == len(self.route) - 1


@dataclass
class Grant:
    """What :meth:`Traffic.extend` did: the new ``held`` index, and the vehicles it waits for (empty
    when it got what it asked or has nothing left to ask)."""

    held: int
    waits_for: frozenset = field(default_factory=frozenset)


def corridors(graph: nx.Graph) -> dict[frozenset, int]:
    """The corridor of each two-way edge (as a frozenset of its two nodes; every edge of an
    undirected graph, the edges without ``oneway`` of a directed one): edges chained through nodes
    with exactly two neighbours share one; numbered in the order of the graph's edges."""
    out: dict[frozenset, int] = {}
    oneway = {frozenset((u, v)) for u, v, one in graph.edges(data="oneway") if one}
    if graph.is_directed():
        graph = graph.to_undirected(as_view=True)
    for u, v in graph.edges:
        if frozenset((u, v)) in out or frozenset((u, v)) in oneway:
            continue
        cid, todo = max(out.values(), default=-1) + 1, [(u, v)]
        while todo:
            a, b = todo.pop()
            key = frozenset((a, b))
            if key in out or key in oneway:
                continue
            out[key] = cid
            for n in (a, b):
                if graph.degree(n) == 2:
                    todo += [(n, w) for w in graph.neighbors(n)]
    return out


class Traffic:
    """Reservations of the vehicles on ``graph`` (module docstring)."""

    def __init__(self, graph: nx.Graph):
        self.graph = graph
        self.holder: dict[str, str] = {}
        """Node id -> the serial number of the vehicle holding it."""
        self.plans: dict[str, Plan] = {}
        self.waiting: dict[str, frozenset] = {}
        """Serial number -> the vehicles it waits for."""
        self.refresh()

    def refresh(self) -> None:
        """Recount the corridors (after a node was added to the graph)."""
        self._corridor = corridors(self.graph)
        roads = self.graph.to_undirected(as_view=True) if self.graph.is_directed() else self.graph
        self._dead_ends = {
            cid for edge, cid in self._corridor.items() if any(roads.degree(n) == 1 for n in edge)
        }
        self._boxes = (
            {n for n, kind in self.graph.nodes(data="kind") if kind == "junction"}
            if self.graph.is_directed()
            else set()
        )
        self._ahead = LOOKAHEAD_NODES if self.graph.is_directed() else None

    def place(self, serial: str, node: str) -> bool:
        """The vehicle stands at ``node`` with no route: it holds that node alone. False if another
        vehicle holds it."""
        if self.holder.get(node, serial) != serial:
            return False
        self._release(serial, keep={node})
        self.holder[node] = serial
        self.plans[serial] = Plan([node])
        self.waiting.pop(serial, None)
        return True

    def assign(self, serial: str, route: list[str]) -> Plan:
        """Give the vehicle ``route`` from the node it stands at (``route[0]``, held by it)."""
        plan = self.plans.get(serial)
        if plan is None or plan.route[plan.passed] != route[0]:
            raise ValueError(f"{serial}: a route must start where the vehicle stands")
        self.plans[serial] = Plan(list(route))
        return self.plans[serial]

    def reroute(self, serial: str, rest: list[str]) -> Plan:
        """Replace the route beyond the last node released (``rest[0]`` must be that node)."""
        plan = self.plans[serial]
        if rest[0] != plan.route[plan.held]:
            raise ValueError(f"{serial}: a new way must start at the last node released")
        plan.route = plan.route[: plan.held] + list(rest)
        return plan

    def run(self, route: list[str], start: int) -> int:
        """The index where the way from ``route[start]`` through the next edge's corridor ends (the
        next node, on a one-way edge)."""
        cid = self._corridor.get(frozenset(route[start : start + 2]))
        end = start + 1
        if cid is None:
            return end
        while end + 1 < len(route) and self._corridor.get(frozenset(route[end : end + 2])) == cid:
            end += 1
        return end

    def dead_end_nodes(self) -> set[str]:
        """The nodes of the dead ends (corridors ending in a node with one edge: docks)."""
        return {n for edge, cid in self._corridor.items() if cid in self._dead_ends for n in edge}

    def _into_dead_end(self, route: list[str], index: int) -> bool:
        return self._corridor.get(frozenset(route[index : index + 2])) in self._dead_ends

    def extend(self, serial: str) -> Grant:
        """Reserve as many whole corridor runs ahead of the vehicle as are free; a run ending at
        the mouth of a dead end (a dock) only together with the run into it, one ending in a
        junction of a directed roadmap only with the next run."""
        plan = self.plans[serial]
        blockers: set[str] = set()
        while plan.held < len(plan.route) - 1:
            if self._ahead is not None and plan.held - plan.passed >= self._ahead:
                break
            end = self.run(plan.route, plan.held)
            while end < len(plan.route) - 1 and (
                self._into_dead_end(plan.route, end) or plan.route[end] in self._boxes
            ):
                end = self.run(plan.route, end)
            need = plan.route[plan.held + 1 : end + 1]
            blockers = {self.holder[n] for n in need if self.holder.get(n, serial) != serial}
            if blockers:
                break
            for n in need:
                self.holder[n] = serial
            plan.held = end
        if blockers:
            self.waiting[serial] = frozenset(blockers)
        else:
            self.waiting.pop(serial, None)
        return Grant(plan.held, frozenset(blockers))

    def advance(self, serial: str, index: int) -> None:
        """The vehicle passed ``route[index]``: the nodes behind it are freed."""
        plan = self.plans[serial]
        if not plan.passed <= index <= plan.held:
            raise ValueError(f"{serial}: passed index {index} outside {plan.passed}..{plan.held}")
        plan.passed = index
        self._release(serial, keep=set(plan.route[index : plan.held + 1]))

    def _release(self, serial: str, keep: set) -> None:
        for node in [n for n, s in self.holder.items() if s == serial and n not in keep]:
            del self.holder[node]

    def held_by(self, serial: str) -> list[str]:
        return [n for n, s in self.holder.items() if s == serial]

    def deadlock(self) -> list[str] | None:
        """A cycle of vehicles each waiting for the next (serial numbers), or None. On a directed
        roadmap only vehicles standing at their last released node count: one with nodes ahead
        moves on and frees the node behind it."""
        waits = nx.DiGraph()
        for serial, others in sorted(self.waiting.items()):
            plan = self.plans[serial]
            if self._ahead is not None and plan.held > plan.passed:
                continue
            waits.add_edges_from((serial, o) for o in sorted(others))
        try:
            return [u for u, _v in nx.find_cycle(waits)]
        except nx.NetworkXNoCycle:
            return None
