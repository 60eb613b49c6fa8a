"""The twin live over the Foxglove WebSocket protocol: ``amr-twin run ... --live``.

Reasons and measurements: docs/how-to/live.md#amr_twinlivefoxglove."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from amr_twin.live import inputs as live_inputs
from amr_twin.recording.event_log import DIAGNOSTIC_ARRAY, has_events, mcap_items
from amr_twin.live.foxglove_clients import SERVICE, FoxgloveClients
from amr_twin.live.rows import LiveRows
from amr_twin.recording.mcap_log import BATTERY_EVERY_ROWS, BUS_TOPICS, _state_items
from amr_twin.ros.geometry_messages import TFMessage
from amr_twin.ros.messages import String
from amr_twin.ros.ros2_cdr import (
    encode_battery_state,
    encode_float64_multi_array,
    encode_string,
    encode_tf_message,
)
from amr_twin.ros.ros2_schemas import msgdef, ros2_type
from amr_twin.ros.ros_state import StateSampler

SCENE_TOPIC = "/twin/scene"
GOAL_TOPIC = "/goal_pose"
GOAL_TYPE = "geometry_msgs/PoseStamped"
GHOST_PERIOD_US = 100_000
"""Period of the scene's ground-truth robot, us (10 Hz)."""
STATE_TOPICS = {
    "/clock": "rosgraph_msgs/Clock",
    "/twin/ground_truth": "nav_msgs/Odometry",
    "/joint_states": "sensor_msgs/JointState",
    "/tf": "tf2_msgs/TFMessage",
    "/twin/true_rpm": "std_msgs/Float64MultiArray",
    "/twin/pwm_counts": "std_msgs/Float64MultiArray",
    "/twin/motor_current": "std_msgs/Float64MultiArray",
    "/battery_state": "sensor_msgs/BatteryState",
    "/robot_description": "std_msgs/String",
    "/tf_static": "tf2_msgs/TFMessage",
    "/twin/collisions": DIAGNOSTIC_ARRAY,
    "/twin/faults": DIAGNOSTIC_ARRAY,
}
"""The recording's topics that are not bus topics (mcap_log, event_log), with their types."""
LATCHED = ("/tf_static", "/robot_description", SCENE_TOPIC)
STATE_ITEM_TOPICS = ("/clock", "/twin/ground_truth", "/joint_states", "/tf")
"""The topics of mcap_log._state_items."""


def live_topics(twin) -> dict[str, str]:
    """Topic -> type of the channels a live twin advertises: the ``.mcap``'s for this twin."""
    sensors = "lidar" in twin.sensors
    skip = set() if sensors else {"scan", "imu/data_raw", "imu/mag"}
    if "uwb" not in twin.sensors:
        skip.add("uwb/range")
    if twin.actors is None:
        skip.add("actors/poses")
    topics = {
        topic: typ for bus_topic, (topic, typ, _enc) in BUS_TOPICS.items() if bus_topic not in skip
    }
    topics.update(STATE_TOPICS)
    return topics


class FoxgloveSink:
    """Serve ``twin`` live over the Foxglove WebSocket protocol, fed by ``pacer``.

    Parameters
    ----------
    twin : Twin
        The twin (built, not yet run); a bus tap and a grid sampler are attached to it.
    pacer : Pacer
        Runs the clients' messages in the twin's thread and calls :meth:`flush`.
    host, port : str, int
        Where the server listens (port 0: a free port, see :attr:`port`).
    """

    def __init__(self, twin, pacer, host: str = "127.0.0.1", port: int = 8765):
        import foxglove
        from foxglove.channels import SceneUpdateChannel

        from amr_twin.live.scene import SceneBuilder

        self.twin, self.pacer, self.bus = twin, pacer, twin.bus
        self._ctx = foxglove.Context()
        self.channels = {}
        for topic, typ in live_topics(twin).items():
            schema = foxglove.Schema(
                name=ros2_type(typ), encoding="ros2msg", data=msgdef(typ).encode()
            )
            self.channels[topic] = foxglove.Channel(
                topic, message_encoding="cdr", schema=schema, context=self._ctx
            )
        self.scene_channel = SceneUpdateChannel(SCENE_TOPIC, context=self._ctx)
        self.goal_channel = foxglove.Channel(
            GOAL_TOPIC,
            message_encoding="cdr",
            context=self._ctx,
            schema=foxglove.Schema(
                name=ros2_type(GOAL_TYPE), encoding="ros2msg", data=msgdef(GOAL_TYPE).encode()
            ),
        )
        self.scene = SceneBuilder(twin.observables.model, twin.observables.named)
        self._bus_out: list[tuple[int, int, object, bytes]] = []  # t_ns, seq, channel, payload
        self._actor_scenes: list[tuple[int, list]] = []  # t_ns, actor poses for the scene
        self._seq = 0
        self._state = StateSampler(twin.observables.model, twin.observables.named)
        self._rows = LiveRows(
            twin
        )  # true wheel speeds, PWM, currents, battery: the recorder's columns
        self._events_sent: set[tuple[str, int]] = set()
        self._collisions_sent = 0
        self._latched_due: set[str] = set(LATCHED)
        self.clients = FoxgloveClients(twin, pacer, self.goal_channel, LATCHED, self._latched_due)
        twin.on_message(self._tap)
        twin.on_grid(self._on_grid)
        self._on_grid(twin.t_phys_us)
        self._capacity_ah = twin.cfg.battery.capacity_ah
        service = foxglove.Service(
            SERVICE, schema=self._service_schema(foxglove), handler=self.clients.on_service_call
        )
        caps = foxglove.Capability
        try:
            self.server = foxglove.start_server(
                name="amr-twin",
                host=host,
                port=port,
                context=self._ctx,
                server_listener=self.clients.listener(foxglove),
                capabilities=[caps.ClientPublish, caps.Services, caps.Time],
                supported_encodings=["cdr", "json"],
                services=[service],
            )
        except RuntimeError as exc:  # foxglove's FoxgloveError, e.g. the port taken since the check
            twin.unhook(self._tap)
            twin.unhook(self._on_grid)
            twin.unhook(self._rows._on_grid)
            raise OSError(f"--port {port}: cannot serve on {host}:{port}: {exc}") from None
        self.host, self.port = host, self.server.port

    @property
    def dropped(self) -> int:
        """Client messages refused so far (each logged; :class:`FoxgloveClients`)."""
        return self.clients.dropped

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    @staticmethod
    def _service_schema(foxglove):
        def message(name: str, text: str):
            return foxglove.MessageSchema(
                encoding="cdr",
                schema=foxglove.Schema(name=name, encoding="ros2msg", data=text.encode()),
            )

        return foxglove.ServiceSchema(
            live_inputs.SERVICE_TYPE,
            request=message(live_inputs.SERVICE_TYPE + "_Request", live_inputs.SERVICE_REQUEST_DEF),
            response=message(live_inputs.SERVICE_TYPE + "_Response", ""),
        )

    # -- the twin's side (its thread) ---------------------------------------------------
    def _tap(self, topic: str, msg, t_us: int) -> None:
        if topic == "actors/poses" and self.scene_channel.has_sinks():
            poses = [(p.position.x, p.position.y, p.orientation.yaw_rad()) for p in msg.poses]
            self._actor_scenes.append((t_us * 1000, poses))
        entry = BUS_TOPICS.get(topic)
        if entry is None:
            return
        channel = self.channels.get(entry[0])
        if channel is None or not channel.has_sinks():
            return
        self._seq += 1
        self._bus_out.append((t_us * 1000, self._seq, channel, entry[2](msg)))

    def _on_grid(self, t_us: int) -> None:
        """Grid sampler (physics at ``t_us``): the joint and base state."""
        self._state.sample(t_us)

    def flush(self, t_us: int) -> None:
        """Send everything up to ``t_us`` (simulated), in time order; broadcast the time."""
        t_ns = t_us * 1000
        for topic in sorted(self._latched_due):
            self._send_latched(topic, t_ns)
        self._latched_due.clear()
        items = [(t, 0, s, ch, data) for t, s, ch, data in self._bus_out]
        self._bus_out = []
        batch = self._state.split(
            t_us
        )  # taken in any case; turned into messages only for a subscriber
        if batch.t_us and any(self.channels[t].has_sinks() for t in STATE_ITEM_TOPICS):
            order = 0
            for t, _k, topic, _typ, data in _state_items(SimpleNamespace(state=batch), 0):
                order += 1
                items.append((t, 1, order, self.channels[topic], data))
        if batch.t_us and self.scene_channel.has_sinks():
            for i, tb in enumerate(batch.t_us):
                if tb % GHOST_PERIOD_US == 0:
                    pos, quat = self._state_pose(batch, i)
                    self.scene_channel.log(
                        self.scene.ghost_update(tb * 1000, pos, quat), log_time=tb * 1000
                    )
        for t, poses in self._actor_scenes:
            self.scene_channel.log(self.scene.actors_update(t, poses), log_time=t)
        self._actor_scenes = []
        rows = self._rows.take(t_us)
        if rows is not None:
            items += self._row_items(rows)
        if has_events(self.twin):
            items += self._event_items(t_ns)
        items.sort(key=lambda it: (it[0], it[1], it[2]))
        for t, _g, _o, channel, data in items:
            channel.log(data, log_time=t)
        self.server.broadcast_time(t_ns)

    def _row_items(self, rows) -> list:
        """/twin/true_rpm, /twin/pwm_counts, /twin/motor_current (100 Hz) and /battery_state (10
        Hz), as mcap_log writes them, for the channels someone subscribed to."""
        out = []
        t_ns = (rows.t_us * 1000).tolist()
        for name, column in (
            ("/twin/true_rpm", rows.true_rpm),
            ("/twin/pwm_counts", rows.pwm_counts),
            ("/twin/motor_current", rows.current_a),
        ):
            channel = self.channels[name]
            if channel.has_sinks():
                values = column.tolist()
                out += [
                    (t, 2, i, channel, encode_float64_multi_array(v))
                    for i, (t, v) in enumerate(zip(t_ns, values))
                ]
        channel = self.channels["/battery_state"]
        if channel.has_sinks():
            cap = self._capacity_ah
            volts, amps, soc = (
                rows.battery_v.tolist(),
                rows.battery_a.tolist(),
                rows.battery_soc.tolist(),
            )
            out += [
                (
                    t,
                    2,
                    i,
                    channel,
                    encode_battery_state(t, volts[i], -amps[i], soc[i] * cap, cap, soc[i]),
                )
                for i, t in enumerate(t_ns)
                if rows.index[i] % BATTERY_EVERY_ROWS == 0
            ]
        return out

    @staticmethod
    def _state_pose(batch, i: int):
        """The base's world position and quaternion of a state sample (the ground truth's)."""
        arrays = batch.arrays()
        return arrays["pos"][i], arrays["quat"][i]

    def _event_items(self, t_ns: int) -> list:
        out = []
        for t, _k, topic, _typ, data in mcap_items(self.twin, 0):
            if t <= t_ns and (topic, t) not in self._events_sent:
                self._events_sent.add((topic, t))
                out.append((t, 3, len(self._events_sent), self.channels[topic], data))
        collisions = self.twin.observables.collisions
        if len(collisions) > self._collisions_sent:
            self._collisions_sent = len(collisions)
            points = np.array([(c.x_m, c.y_m, c.z_m) for c in collisions])
            self.scene_channel.log(self.scene.collisions_update(t_ns, points), log_time=t_ns)
        return out

    def _send_latched(self, topic: str, t_ns: int) -> None:
        if topic == "/robot_description":
            self.channels[topic].log(encode_string(String(self.twin.urdf)), log_time=t_ns)
        elif topic == "/tf_static":
            self.channels[topic].log(
                encode_tf_message(TFMessage(self.bus.static_transforms())), log_time=t_ns
            )
        elif topic == SCENE_TOPIC:
            self.scene_channel.log(self.scene.static_update(t_ns), log_time=t_ns)

    def close(self) -> None:
        """Stop the server (clients are disconnected)."""
        self.server.stop()
