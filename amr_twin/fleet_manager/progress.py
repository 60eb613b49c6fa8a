"""What the manager knows of each vehicle and of the task it gave it, and how a vehicle's VDA 5050
state says a task finished or failed.

A task is a job (pick, then drop), a park (make way) or a charge; its order runs through its stops
on the roadmap, each stop with its node actions. A task is finished when the vehicle reports the
order's last node passed with nothing left (no nodeStates, not driving) and every action of the task
FINISHED; it failed when an error names its orderId or one of its actions FAILED.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from amr_twin.fleet_manager import messages as vda
from amr_twin.fleet_manager.jobs import Job

DONE = ("FINISHED", "FAILED")


@dataclass
class Vehicle:
    """A vehicle as the manager sees it: the node it stands at (None while it drives a task), its
    last state, the node actions its factsheet lists (None: none received yet)."""

    serial: str
    node: str | None = None
    state: dict | None = None
    states: int = 0
    online: bool = False
    node_actions: frozenset | None = None
    task: Task | None = None
    tasks: int = 0
    moved: bool = False
    """Whether it was given a task (one just placed is left where it stands)."""

    def can(self, action_type: str) -> bool:
        """Whether it performs the node action (assumed until its factsheet says otherwise)."""
        return self.node_actions is None or action_type in self.node_actions

    def counter(self) -> int:
        self.tasks += 1
        return self.tasks


@dataclass
class Task:
    """An order's stops (node id, node actions) and what was sent of it."""

    kind: str
    order_id: str
    stops: list[tuple[str, list[dict]]]
    job: Job | None = None
    update_id: int = 0
    sent_held: int = 0
    actions: dict[int, list[dict]] = field(default_factory=dict)
    stop_at: list[int] = field(default_factory=list)
    waiting: bool = False
    stop_sent: bool = False
    resume: list = field(default_factory=list)
    """The stops still ahead after a side-step, taken up when the vehicle stands at its spot."""
    yield_to: frozenset = frozenset()
    """The vehicles a side-step lets by."""
    detoured: int = -1
    """The route index it stood at when last given a detour (none again before it moves on)."""

    @classmethod
    def job_task(cls, job: Job, node_actions: frozenset | None) -> Task:
        """Pick at ``job.pick`` and drop at ``job.drop`` (each only if the vehicle performs it)."""
        stops = []
        for node, kind in ((job.pick, "pick"), (job.drop, "drop")):
            ok = node_actions is None or kind in node_actions
            stops.append((node, [vda.load_action(kind, job.job_id, node, job.payload_kg)] * ok))
        return cls("job", job.job_id, stops, job)

    @classmethod
    def charge(cls, order_id: str, node: str) -> Task:
        return cls("charge", order_id, [(node, [vda.action(f"{order_id}-start", "startCharging")])])

    @classmethod
    def park(cls, order_id: str, node: str) -> Task:
        return cls("park", order_id, [(node, [])])

    def route_from(self, roadmap, start: str, avoid=frozenset()) -> list[str] | None:
        """The route from ``start`` through the stops (None if there is none); sets
        :attr:`actions` (route index -> node actions) and :attr:`stop_at` (each stop's index)."""
        found = self._through(roadmap, start, 0, self.stops, avoid)
        if found is None:
            return None
        way, self.actions, self.stop_at = found
        return way

    def reroute(self, roadmap, node: str, index: int, avoid) -> list[str] | None:
        """A new way from ``node`` (route index ``index``, the last released) through the stops
        still ahead, around ``avoid``; None if there is none (then nothing changes)."""
        ahead = [k for k, i in enumerate(self.stop_at) if i > index]
        found = self._through(roadmap, node, index, [self.stops[k] for k in ahead], avoid)
        if found is None:
            return None
        way, actions, stop_at = found
        self.actions = {**{i: a for i, a in self.actions.items() if i <= index}, **actions}
        self.stop_at = [i for i in self.stop_at if i <= index] + stop_at
        return way

    def detour(self, roadmap, node: str, index: int, spot: str, avoid) -> list[str] | None:
        """A way from ``node`` (route index ``index``) to ``spot`` alone, the stops ahead kept in
        :attr:`resume`; None if there is none or no stop is ahead (then nothing changes)."""
        ahead = [k for k, i in enumerate(self.stop_at) if i > index]
        leg = roadmap.route(node, spot, avoid)
        if leg is None or not ahead:
            return None
        self.resume = [self.stops[k] for k in ahead]
        self.actions = {i: a for i, a in self.actions.items() if i <= index}
        self.stop_at = [i for i in self.stop_at if i <= index]
        return leg

    def way_on(self, roadmap, node: str, index: int, avoid):
        """The way on from ``node`` (route index ``index``) through :attr:`resume`, with its
        actions and stop indices, or None (nothing changes: :meth:`take_up` takes it)."""
        return self._through(roadmap, node, index, self.resume, avoid)

    def take_up(self, found) -> list[str]:
        """Take up the way :meth:`way_on` found; returns the way."""
        way, actions, stop_at = found
        self.actions.update(actions)
        self.stop_at += stop_at
        self.resume = []
        return way

    @staticmethod
    def _through(roadmap, start: str, offset: int, stops, avoid):
        """(way from ``start``, its actions and stop indices counted from ``offset``) or None."""
        way, actions, stop_at = [start], {}, []
        for node, acts in stops:
            leg = roadmap.route(way[-1], node, avoid)
            if leg is None:
                return None
            way += leg[1:]
            stop_at.append(offset + len(way) - 1)
            if acts:
                actions.setdefault(offset + len(way) - 1, []).extend(acts)
        return way, actions, stop_at

    def ids(self) -> list[str]:
        out = [a["actionId"] for acts in self.actions.values() for a in acts]
        return out + ([f"{self.order_id}-stop"] if self.kind == "charge" else [])

    def charging_started(self, state: dict) -> bool:
        return _status(state).get(f"{self.order_id}-start") == "FINISHED"


def _status(state: dict) -> dict[str, str]:
    return {a.get("actionId"): a.get("actionStatus") for a in state.get("actionStates", [])}


def task_finished(state: dict, task: Task, plan, resumed: bool = True) -> bool:
    """Whether ``state`` reports ``task`` done (module docstring); ``resumed`` False: whether its
    route is driven to the end, stops left after a side-step or not."""
    if not plan.done or state.get("orderId") != task.order_id:
        return False
    if state.get("nodeStates") or state.get("driving"):
        return False
    if not resumed:
        return True
    if task.resume:
        return False
    if task.kind == "charge" and not task.stop_sent:
        return False
    status = _status(state)
    return all(status.get(i) in DONE for i in task.ids())


def order_failed(state: dict, task: Task) -> str | None:
    """Why ``task`` failed (an error naming its orderId, an action FAILED), or None."""
    for err in state.get("errors", []):
        refs = {
            r.get("referenceKey"): r.get("referenceValue") for r in err.get("errorReferences", [])
        }
        if refs.get("orderId") == task.order_id:
            return f"{err.get('errorType')}: {err.get('errorDescription', '')}"
    status = _status(state)
    for action_id in task.ids():
        if status.get(action_id) == "FAILED":
            return f"action {action_id} failed"
    return None
