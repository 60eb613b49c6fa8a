"""Vehicles that follow VDA 5050 orders on the roadmap without physics, for the fleet manager's
tests: each step a vehicle moves to its next released node (or stays), and reports its state."""

from __future__ import annotations


class FakeVehicle:
    """One vehicle at ``node``: takes orders and updates (stitched at the last base node), moves a
    node a step, finishes a node's actions when it gets there."""

    def __init__(self, serial: str, roadmap, node: str):
        self.serial, self.roadmap, self.node = serial, roadmap, node
        self.order_id, self.seq, self.nodes, self.actions = "", 0, [], {}
        self.base = (node, 0)

    def receive(self, subtopic: str, msg: dict) -> None:
        if subtopic == "instantActions":
            for a in msg["actions"]:
                self.actions[a["actionId"]] = (a["actionType"], "FINISHED")
            return
        first = msg["nodes"][0]
        if msg["orderId"] == self.order_id:  # an update: stitched at the last base node
            assert (first["nodeId"], first["sequenceId"]) == self.base, (
                self.serial,
                msg,
                self.base,
            )
        else:  # a new order: from where the vehicle stands
            assert first["nodeId"] == self.node and not self.nodes, (self.serial, msg, self.node)
        self.base = max(
            ((n["nodeId"], n["sequenceId"]) for n in msg["nodes"] if n["released"]),
            key=lambda b: b[1],
        )
        if msg["orderId"] != self.order_id:
            self.order_id, self.seq, self.nodes = msg["orderId"], first["sequenceId"], msg["nodes"]
            self.actions = {}
        else:
            self.nodes = [n for n in self.nodes if n["sequenceId"] < first["sequenceId"]]
            self.nodes += msg["nodes"]
        self._arrive(self.nodes[0])

    def _arrive(self, node: dict) -> None:
        self.node, self.seq = node["nodeId"], node["sequenceId"]
        self.nodes = [n for n in self.nodes if n["sequenceId"] > self.seq]
        for a in node["actions"]:
            self.actions[a["actionId"]] = (a["actionType"], "FINISHED")

    def step(self) -> None:
        if self.nodes and self.nodes[0]["released"]:
            self._arrive(self.nodes[0])

    def state(self, charge: float = 90.0) -> dict:
        x, y = self.roadmap.xy(self.node)
        return {
            "orderId": self.order_id,
            "lastNodeId": self.node,
            "lastNodeSequenceId": self.seq,
            "nodeStates": [{"nodeId": n["nodeId"]} for n in self.nodes],
            "edgeStates": [],
            "driving": False,
            "agvPosition": {"x": x, "y": y, "theta": 0.0, "mapId": self.roadmap.map_id},
            "batteryState": {"batteryCharge": charge},
            "actionStates": [
                {"actionId": k, "actionType": t, "actionStatus": s}
                for k, (t, s) in self.actions.items()
            ],
            "errors": [],
        }


FACTSHEET = {
    "protocolFeatures": {
        "agvActions": [{"actionType": t, "actionScopes": ["NODE"]} for t in ("pick", "drop")]
    }
}
"""A factsheet listing pick and drop as node actions."""


def drive(roadmap, vehicles: int, jobs: int, seed: int, steps: int = 600, pool_docks=False):
    """Run ``vehicles`` fake vehicles (started on rack faces spread over the roadmap) under the
    fleet manager on ``jobs`` seeded jobs until done or ``steps`` steps, asserting at every step
    that no two stand on one node or drive one edge; returns (jobs done, steps taken, events)."""
    from amr_twin.fleet_manager.dispatcher import Dispatcher, ManagerOptions
    from amr_twin.fleet_manager.jobs import job_stream

    charging = (roadmap.nodes_of("end") or roadmap.nodes_of("junction"))[0]
    d = Dispatcher(roadmap, ManagerOptions(charging_nodes=(charging,), pool_docks=pool_docks))
    faces = roadmap.nodes_of("aisle")
    starts = faces[:: len(faces) // vehicles][:vehicles]
    fleet = {f"amr-{i + 1}": FakeVehicle(f"amr-{i + 1}", roadmap, s) for i, s in enumerate(starts)}

    def deliver(out):
        for serial, sub, msg in out:
            fleet[serial].receive(sub, msg)

    for serial, v in fleet.items():
        deliver(d.on_connection(serial, {"connectionState": "ONLINE"}))
        deliver(d.on_factsheet(serial, FACTSHEET))
        deliver(d.on_state(serial, v.state()))
    deliver(d.submit(job_stream(roadmap, jobs, seed, exclude={charging})))
    done, step = 0, 0
    for step in range(1, steps + 1):
        moves = {}
        for serial, v in fleet.items():
            before = v.node
            v.step()
            if v.node != before:
                moves[serial] = frozenset((before, v.node))
            deliver(d.on_state(serial, v.state()))
        at = [v.node for v in fleet.values()]
        assert len(set(at)) == len(at), at  # no two on one node
        assert len(set(moves.values())) == len(moves), moves  # no two on one edge
        done = sum(e["event"] == "done" and e.get("task") == "job" for e in d.events)
        if done == jobs:
            break
    return done, step, d.events
