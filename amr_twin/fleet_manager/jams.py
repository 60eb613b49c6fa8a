"""Jams and how the fleet manager clears them, on the
:class:`~amr_twin.fleet_manager.dispatcher.Dispatcher`'s vehicles and reservations:

- an idle vehicle at a dock leaves its dead end (docks are for loading; one parked there boxes
  itself in);
- an idle vehicle in another's way is parked at the nearest free node off it; one boxed in by the
  vehicle waiting for it is let out (that vehicle side-steps to a spot from which it can get out);
- a deadlock (a cycle of waiting vehicles) is broken by a detour
  (:func:`~amr_twin.fleet_manager.detours.break_cycle`) and reported;
- a vehicle that side-stepped takes up its stops once it crosses no way of those it let by.
"""

from __future__ import annotations

from amr_twin.fleet_manager.detours import break_cycle, exit_way, free_spot, side_step
from amr_twin.fleet_manager.progress import Task, Vehicle


class Jams:
    """The jams of dispatcher ``d`` (module docstring)."""

    def __init__(self, d):
        self.d = d
        self.evict: dict[str, set] = {}
        """Idle vehicles to park once they can get out, and the nodes to keep clear."""
        self.reported: set = set()
        """The deadlock cycle last reported."""

    def resume(self, v: Vehicle) -> None:
        """After a side-step: the way on from where ``v`` stands through its stops ahead, once it
        crosses no way of the vehicles it let by (or another vehicle waits for it)."""
        self.d.extend_all()  # the vehicles let by take what the side-step freed, first
        plan, task = self.d.traffic.plans[v.serial], v.task
        parked = {o.node for s, o in self.d.idle().items() if s != v.serial}
        here = plan.route[plan.passed]
        found = task.way_on(self.d.roadmap, here, plan.passed, parked)
        found = found or task.way_on(self.d.roadmap, here, plan.passed, frozenset())
        if found is None:
            return
        let_by = [  # those still driving on (not waiting, not standing aside themselves)
            self.d.traffic.plans[o]
            for o in task.yield_to
            if self.d.vehicles[o].task
            and not self.d.vehicles[o].task.resume
            and o not in self.d.traffic.waiting
        ]
        crosses = any(set(found[0][1:]) & set(p.route[p.passed :]) for p in let_by)
        waited = any(v.serial in others for others in self.d.traffic.waiting.values())
        if crosses and not waited:
            return
        self.d.traffic.reroute(v.serial, task.take_up(found))
        self.d.update(v)  # the new horizon; released by the next extension

    def make_way(self) -> None:
        """Idle vehicles in another's way sent off it; one boxed in by the vehicle waiting for it
        (a dead end) is let out: that vehicle side-steps and waits until it is parked."""
        charging = self.d.options.charging_nodes
        for serial, blockers in sorted(self.d.traffic.waiting.items()):
            plan = self.d.traffic.plans[serial]
            ahead = set(plan.route[plan.held :])
            for b in sorted(blockers):
                v = self.d.vehicles[b]
                if v.task is None and v.node is not None and v.node in ahead:
                    if self.park(v, ahead):
                        continue

                    def gets_out(v=v, ahead=ahead) -> bool:
                        traffic, node = self.d.traffic, v.node
                        return bool(
                            free_spot(self.d.roadmap, traffic, v.serial, node, ahead, charging)
                        )

                    if side_step(
                        self.d.roadmap,
                        self.d.traffic,
                        serial,
                        self.d.vehicles[serial].task,
                        [serial, b],
                        charging,
                        exit_way(self.d.roadmap, v.node),
                        unbox=(b, gets_out),
                    ):
                        self.d.update(self.d.vehicles[serial])
                        self.evict[b] = ahead
                        self.d.event("side-step", vehicle=serial, lets_out=b)
        for b, keep_clear in sorted(self.evict.items()):
            v = self.d.vehicles[b]
            if v.task is not None or self.park(v, keep_clear):
                del self.evict[b]

    def stuck(self) -> set:
        """Vehicles standing aside for an idle vehicle that cannot be parked off their way."""
        out = set()
        for b, keep_clear in self.evict.items():
            charging = self.d.options.charging_nodes
            node = self.d.vehicles[b].node
            if free_spot(self.d.roadmap, self.d.traffic, b, node, keep_clear, charging) is None:
                out |= {s for s, v in self.d.vehicles.items() if v.task and b in v.task.yield_to}
        return out

    def clear_docks(self) -> None:
        """An idle vehicle at a dock (not a charging node) leaves its dead end for an aisle node off
        the others' ways: docks are for loading, and a vehicle parked in one boxes itself in. One
        idle elsewhere after a task, on a roadmap with lay-bys, goes to a free lay-by, off the
        through lanes."""
        docks = set(self.d.roadmap.nodes_of("end")) - set(self.d.options.charging_nodes)
        keep = self.d.traffic.dead_end_nodes() | set(self.d.roadmap.nodes_of("junction"))
        ways = {n for p in self.d.traffic.plans.values() for n in p.route[p.passed :]}
        bays = {n for n, bay in self.d.roadmap.graph.nodes(data="bay") if bay}
        for v in self.d.idle().values():
            if v.node in docks:
                if not self.park(v, keep | ways):
                    self.park(v, keep)
            elif v.moved and bays and v.node not in bays | set(self.d.options.charging_nodes):
                self.park(v, keep | ways, bays_only=True)

    def park(self, v: Vehicle, keep_clear: set, bays_only: bool = False) -> bool:
        """Send idle ``v`` to the nearest free node off ``keep_clear``: a lay-by (a node with
        ``bay`` true) if it can, else (unless ``bays_only``) one out of the dead ends if it can;
        False if there is none."""
        charging, spurs = self.d.options.charging_nodes, self.d.traffic.dead_end_nodes()
        graph = self.d.roadmap.graph
        off_bays = {n for n, bay in graph.nodes(data="bay") if not bay}
        spot = None
        if len(off_bays) < len(graph):  # lay-bys off the through lanes first
            spot = free_spot(
                self.d.roadmap, self.d.traffic, v.serial, v.node, keep_clear | off_bays, charging
            )
        if spot is None and bays_only:
            return False
        spot = spot or free_spot(
            self.d.roadmap, self.d.traffic, v.serial, v.node, keep_clear | spurs, charging
        )
        spot = spot or free_spot(
            self.d.roadmap, self.d.traffic, v.serial, v.node, keep_clear, charging
        )
        others = {n for n, s in self.d.traffic.holder.items() if s != v.serial}
        if spot is None:
            return False
        return self.d.start(v, Task.park(f"{v.serial}-park-{v.counter()}", spot), others)

    def break_deadlock(self) -> None:
        cycle = self.d.traffic.deadlock()
        if cycle is None:
            self.reported.clear()
            return
        key = tuple(sorted(cycle))
        tasks = {s: self.d.vehicles[s].task for s in cycle}
        detour = break_cycle(
            self.d.roadmap, self.d.traffic, tasks, cycle, self.d.options.charging_nodes
        )
        if detour is not None:
            v = self.d.vehicles[detour.serial]
            v.task.waiting = bool(self.d.traffic.extend(detour.serial).waits_for)
            self.d.update(v)
        if key in self.reported and detour is None:
            return  # reported, still no way out
        self.reported = {key}
        self.d.event(
            "deadlock",
            vehicles=list(cycle),
            rerouted=detour.serial if detour else None,
            how=detour.kind if detour else None,
        )
