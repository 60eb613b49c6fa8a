"""The fleet manager's decisions, from the vehicles' VDA 5050 messages to the orders it sends (no
MQTT here: :class:`~amr_twin.fleet_manager.manager.FleetManager` carries the messages).

- A vehicle is placed on the roadmap at its first state (its node, or a ``home`` node joined to the
  nearest one) and asked for its factsheet, which says whether it performs pick, drop and charging.
- Jobs wait in order of arrival; each goes to the nearest idle vehicle (with pooled docks, its drop
  to the dock with the shortest queue) as one order through the pick and the drop node (node
  actions ``pick`` and ``drop``), released as far as the traffic control
  (:mod:`~amr_twin.fleet_manager.traffic`) reserves and extended by order updates as the vehicle's
  ``lastNodeId`` frees nodes behind it and others'.
- Jams (an idle vehicle in the way or in a dock, a deadlock) are cleared by
  :class:`~amr_twin.fleet_manager.jams.Jams`.
- An idle vehicle whose ``batteryState.batteryCharge`` is below ``charge_below`` % goes to a free
  charging node with ``startCharging``, and gets ``stopCharging`` at ``charge_until`` %.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from amr_twin.fleet_manager import messages as vda
from amr_twin.fleet_manager.jams import Jams
from amr_twin.fleet_manager.jobs import Job, nearest_vehicle
from amr_twin.fleet_manager.progress import Task, Vehicle, order_failed, task_finished
from amr_twin.fleet_manager.traffic import Traffic

FACTSHEET_WAIT_STATES = 5
"""States a vehicle that does not answer factsheetRequest sends before it gets jobs anyway."""


@dataclass(frozen=True)
class ManagerOptions:
    """Charging thresholds (batteryCharge, %), the charging nodes (roadmap node ids), and whether a
    job's drop at a dock may go to any dock (``pool_docks``: the one with the shortest queue)."""

    charge_below: float = 20.0
    charge_until: float = 80.0
    charging_nodes: tuple[str, ...] = ()
    pool_docks: bool = False


@dataclass
class Dispatcher:
    """Jobs, vehicles and reservations on ``roadmap`` (module docstring); each ``on_*`` method
    returns the messages to send, as (serial number, subtopic, message)."""

    roadmap: object
    options: ManagerOptions = field(default_factory=ManagerOptions)
    clock: object = None

    def __post_init__(self):
        self.traffic = Traffic(self.roadmap.graph)
        self.headers = vda.Headers()
        self.vehicles: dict[str, Vehicle] = {}
        self.pending: list[Job] = []
        self.events: list[dict] = []
        self.jams = Jams(self)
        self._out: list = []

    def vehicle(self, serial: str) -> Vehicle:
        return self.vehicles.setdefault(serial, Vehicle(serial))

    def submit(self, jobs: list[Job]) -> list:
        self.pending += jobs
        return self._decide()

    def on_connection(self, serial: str, msg: dict) -> list:
        v = self.vehicle(serial)
        v.online = msg.get("connectionState") == "ONLINE"
        if v.online and v.node_actions is None:
            self._send(
                serial,
                "instantActions",
                vda.instant(
                    self.headers,
                    serial,
                    [vda.action(f"{serial}-factsheet-{v.counter()}", "factsheetRequest")],
                ),
            )
        return self._flush()

    def on_factsheet(self, serial: str, msg: dict) -> list:
        features = msg.get("protocolFeatures", {}).get("agvActions", [])
        self.vehicle(serial).node_actions = frozenset(
            a.get("actionType") for a in features if "NODE" in a.get("actionScopes", [])
        )
        return self._decide()

    def on_state(self, serial: str, msg: dict) -> list:
        v = self.vehicle(serial)
        v.state, v.states = msg, v.states + 1
        if v.node is None and v.task is None:
            self._place(v)
        elif v.task is not None:
            self._follow(v)
        return self._decide()

    # -- vehicles and tasks -------------------------------------------------------------------
    def _place(self, v: Vehicle) -> None:
        pos = v.state.get("agvPosition")
        if not pos or v.state.get("driving"):
            return
        node = self.roadmap.attach(f"{v.serial}-home", pos["x"], pos["y"])
        self.traffic.refresh()
        if self.traffic.place(v.serial, node):
            v.node = node
            self.event("placed", vehicle=v.serial, node=node)
        else:
            self.event("conflict", vehicle=v.serial, node=node, held_by=self.traffic.holder[node])

    def _follow(self, v: Vehicle) -> None:
        task, plan = v.task, self.traffic.plans[v.serial]
        st = v.state
        if st.get("orderId") == task.order_id:
            i = st.get("lastNodeSequenceId", -1)
            if i % 2 == 0 and plan.passed < i // 2 <= plan.held:
                if plan.route[i // 2] == st.get("lastNodeId"):
                    self.traffic.advance(v.serial, i // 2)
        failed = order_failed(st, task)
        if not failed and task.resume and task_finished(st, task, plan, resumed=False):
            if not task.yield_to & self.jams.evict.keys() or v.serial in self.jams.stuck():
                self.jams.resume(v)
        elif failed or task_finished(st, task, plan):
            v.node = plan.route[plan.passed]
            self.traffic.place(v.serial, v.node)
            self.event(
                "failed" if failed else "done",
                vehicle=v.serial,
                task=task.kind,
                order=task.order_id,
                job=task.job.job_id if task.job else None,
                node=v.node,
                reason=failed,
            )
            v.task = None
        elif task.kind == "charge" and task.charging_started(st):
            if st.get("batteryState", {}).get("batteryCharge", 0.0) >= self.options.charge_until:
                if not task.stop_sent:
                    task.stop_sent = True
                    self._send(
                        v.serial,
                        "instantActions",
                        vda.instant(
                            self.headers,
                            v.serial,
                            [vda.action(f"{task.order_id}-stop", "stopCharging")],
                        ),
                    )

    def start(self, v: Vehicle, task: Task, avoid=frozenset()) -> bool:
        """Route ``task`` from where ``v`` stands, reserve, and send its order; False if no way."""
        way = task.route_from(self.roadmap, v.node, avoid)
        if way is None:
            return False
        self.traffic.assign(v.serial, way)
        v.task, v.node, v.moved = task, None, True
        grant = self.traffic.extend(v.serial)
        task.sent_held = grant.held
        self._send(v.serial, "order", self._order(v.serial, task, 0))
        self.event(
            "assigned",
            vehicle=v.serial,
            task=task.kind,
            order=task.order_id,
            job=task.job.job_id if task.job else None,
            route=way,
        )
        return True

    def _order(self, serial: str, task: Task, first: int) -> dict:
        plan = self.traffic.plans[serial]
        return vda.order(
            self.headers,
            serial,
            task.order_id,
            task.update_id,
            plan.route,
            first,
            plan.held,
            task.actions,
            self.roadmap.position,
        )

    # -- decisions ------------------------------------------------------------------------------
    def _decide(self) -> list:
        self._charge_or_assign()
        self.jams.clear_docks()
        self.extend_all()
        self.jams.make_way()
        self.jams.break_deadlock()
        return self._flush()

    def idle(self) -> dict[str, Vehicle]:
        return {
            s: v
            for s, v in sorted(self.vehicles.items())
            if v.node is not None
            and v.task is None
            and v.online
            and (v.node_actions is not None or v.states >= FACTSHEET_WAIT_STATES)
        }

    def _charge_or_assign(self) -> None:
        for v in self.idle().values():
            charge = v.state.get("batteryState", {}).get("batteryCharge", 100.0)
            if charge < self.options.charge_below and v.can("startCharging"):
                free = [
                    n
                    for n in self.options.charging_nodes
                    if self.traffic.holder.get(n, v.serial) == v.serial
                ]
                target = nearest_vehicle(self.roadmap.graph, {n: n for n in free}, v.node)
                if target is not None:
                    self.start(v, Task.charge(f"{v.serial}-charge-{v.counter()}", target))
        while self.pending:
            idle = {s: v.node for s, v in self.idle().items()}
            serial = nearest_vehicle(self.roadmap.graph, idle, self.pending[0].pick)
            if serial is None:
                return
            v, job = self.vehicles[serial], self.pending.pop(0)
            task = Task.job_task(self._dock_for(job), v.node_actions)
            parked = {n for s, other in self.idle().items() if s != serial for n in [other.node]}
            if not self.start(v, task, parked) and not self.start(v, task):
                self.event("failed", vehicle=serial, job=job.job_id, reason="no way on the map")

    def _dock_for(self, job: Job) -> Job:
        """``job`` with its drop at the dock with the fewest vehicles bound for it (ties: the
        nearest to the pick), if docks are pooled and it drops at a dock."""
        docks = [n for n in self.roadmap.nodes_of("end") if n not in self.options.charging_nodes]
        if not self.options.pool_docks or job.drop not in docks:
            return job
        queue = dict.fromkeys(docks, 0)
        for v in self.vehicles.values():
            if v.task is not None and v.task.job is not None and v.task.job.drop in queue:
                queue[v.task.job.drop] += 1

        def length(dock: str) -> float:
            way = self.roadmap.route(job.pick, dock)
            return self.roadmap.length_m(way) if way else float("inf")

        return replace(job, drop=min(docks, key=lambda n: (queue[n], length(n), n)))

    def extend_all(self) -> None:
        for serial, v in sorted(self.vehicles.items()):
            if v.task is None:
                continue
            before = self.traffic.plans[serial].held
            grant = self.traffic.extend(serial)
            if grant.held > before:
                self.update(v)
            elif grant.waits_for and not v.task.waiting:
                self.event(
                    "wait",
                    vehicle=serial,
                    node=self.traffic.plans[serial].route[before],
                    waits_for=sorted(grant.waits_for),
                )
            v.task.waiting = bool(grant.waits_for)

    def update(self, v: Vehicle) -> None:
        v.task.update_id += 1
        self._send(v.serial, "order", self._order(v.serial, v.task, v.task.sent_held))
        v.task.sent_held = self.traffic.plans[v.serial].held

    # -- output ---------------------------------------------------------------------------------
    def _send(self, serial: str, subtopic: str, msg: dict) -> None:
        self._out.append((serial, subtopic, msg))

    def _flush(self) -> list:
        out, self._out = self._out, []
        return out

    def event(self, kind: str, **fields) -> None:
        t = self.clock() if self.clock is not None else None
        self.events.append({"t_s": t, "event": kind, **fields})
