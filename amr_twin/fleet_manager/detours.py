"""Ways out of a jam: an idle vehicle sent off another's way, and a deadlock broken by a detour.

- :func:`free_spot`: the nearest node a vehicle reaches through nodes no other vehicle holds, off
  the nodes to keep clear (another's way ahead) and off the charging nodes.
- :func:`break_cycle`: for a cycle of vehicles waiting for each other (highest serial number
  first), a new way for one of them through its stops ahead round the nodes the others hold; if no
  vehicle has one, one of them *side-steps*: it drives to a free spot off the others' ways and takes
  up its stops from there once it stands and none of them waits for it any more
  (:attr:`~amr_twin.fleet_manager.progress.Task.resume`).
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx


@dataclass(frozen=True)
class Detour:
    """What :func:`break_cycle` did: the vehicle given a new way, and how (``reroute`` or
    ``side-step``)."""

    serial: str
    kind: str


def free_spots(roadmap, traffic, serial: str, start: str, keep_clear: set, charging) -> list:
    """The nodes vehicle ``serial`` can reach from ``start`` through nodes no other vehicle holds,
    off ``keep_clear`` and the charging nodes, nearest first."""
    others = {n for n, s in traffic.holder.items() if s != serial}
    graph = roadmap.graph.subgraph(n for n in roadmap.graph if n not in others)
    dist = nx.single_source_dijkstra_path_length(graph, start, weight="length_m")
    spots = [
        (d, n) for n, d in dist.items() if n not in keep_clear and n not in charging and n != start
    ]
    return [n for _d, n in sorted(spots)]


def free_spot(roadmap, traffic, serial: str, start: str, keep_clear: set, charging) -> str | None:
    """The nearest of :func:`free_spots`, or None."""
    spots = free_spots(roadmap, traffic, serial, start, keep_clear, charging)
    return spots[0] if spots else None


def lets_out(traffic, serial: str, spot: str, boxed, test) -> bool:
    """Whether ``test()`` holds (the boxed vehicle ``boxed`` finds a spot) with vehicle ``serial``
    standing at ``spot`` alone; the reservations are left as they were."""
    saved = dict(traffic.holder)
    for n in [n for n, s in traffic.holder.items() if s == serial]:
        del traffic.holder[n]
    traffic.holder[spot] = serial
    try:
        return test()
    finally:
        traffic.holder.clear()
        traffic.holder.update(saved)


def break_cycle(roadmap, traffic, tasks: dict, cycle: list[str], charging) -> Detour | None:
    """Give one vehicle of ``cycle`` (serial numbers; ``tasks``: serial -> its task) a detour and
    re-plan it in ``traffic``; None if none has one."""
    order = [s for s in sorted(cycle, reverse=True) if tasks[s].detoured != traffic.plans[s].passed]
    for serial in order:
        plan = traffic.plans[serial]
        held = {n for n, s in traffic.holder.items() if s != serial and s in cycle}
        task = tasks[serial]
        saved = (dict(task.actions), list(task.stop_at))
        rest = task.reroute(roadmap, plan.route[plan.held], plan.held, held)
        if rest is not None and not held & set(rest[1:]):
            traffic.reroute(serial, rest)
            task.detoured = plan.passed
            return Detour(serial, "reroute")
        task.actions, task.stop_at = saved  # no way, or one through a stop another holds
    for serial in order:
        if side_step(roadmap, traffic, serial, tasks[serial], cycle, charging):
            return Detour(serial, "side-step")
    return None


def exit_way(roadmap, node: str) -> set:
    """The nodes from ``node`` to the nearest junction (the way out of its dead end or aisle)."""
    junctions = set(roadmap.nodes_of("junction"))
    dist, paths = nx.single_source_dijkstra(roadmap.graph, node, weight="length_m")
    reach = [(d, n) for n, d in dist.items() if n in junctions]
    return set(paths[min(reach)[1]]) if reach else {node}


def side_step(
    roadmap, traffic, serial: str, task, cycle, charging, clear=frozenset(), unbox=None
) -> bool:
    """Send vehicle ``serial`` (doing ``task``) to a free spot off the ways of all other vehicles
    (else off those of ``cycle``) and off ``clear`` (and, with ``unbox`` = (a boxed vehicle, a test
    that it can get out), one from which it can), to take up its stops later; False if there is
    none."""
    plan = traffic.plans[serial]
    start = plan.route[plan.held]

    def ways(vehicles) -> set:
        return {
            n
            for s in vehicles
            if s != serial
            for n in traffic.plans[s].route[traffic.plans[s].passed :]
        }

    spots = free_spots(roadmap, traffic, serial, start, ways(traffic.plans) | clear, charging)
    spots = spots or free_spots(roadmap, traffic, serial, start, ways(cycle) | clear, charging)
    if unbox is not None:  # only a spot from which the boxed vehicle can get out
        spots = [n for n in spots[:12] if lets_out(traffic, serial, n, *unbox)]
    spot = spots[0] if spots else None
    others = {n for n, s in traffic.holder.items() if s != serial}
    leg = None if spot is None else task.detour(roadmap, start, plan.held, spot, others)
    if leg is None:
        return False
    traffic.reroute(serial, leg)
    task.yield_to, task.detoured = frozenset(cycle) - {serial}, plan.passed
    return True
