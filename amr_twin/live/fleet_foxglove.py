"""A world of several robots live over the Foxglove WebSocket protocol: ``amr-twin fleet ...
--live``.

The channels of the fleet's ``.mcap`` (:mod:`amr_twin.recording.fleet_mcap`): each robot's
topics under its namespace (``/amr-1/odom``, ``/amr-1/scan``, ``/amr-1/battery_state``, ...), its
frames prefixed on the one ``/tf`` and ``/tf_static``, one ``/clock``; the server broadcasts the
simulated time. Read-only: the robots are driven through VDA 5050. Reasons:
docs/how-to/fleet.md#amr_twinlivefleet_foxglove.
"""

from __future__ import annotations

from types import SimpleNamespace

from amr_twin.live.foxglove import live_topics
from amr_twin.live.rows import LiveRows
from amr_twin.assembly.robot_view import RobotView
from amr_twin.recording.fleet_mcap import static_transforms
from amr_twin.recording.mcap_log import BATTERY_EVERY_ROWS, BUS_TOPICS, _state_items
from amr_twin.ros.messages import String
from amr_twin.ros.robot_namespace import RobotNamespace
from amr_twin.ros.ros2_cdr import (
    encode_battery_state,
    encode_clock,
    encode_float64_multi_array,
    encode_string,
    encode_tf_message,
)
from amr_twin.ros.ros2_schemas import msgdef, ros2_type
from amr_twin.ros.ros_state import StateSampler, clock

ROW_TOPICS = ("/twin/true_rpm", "/twin/pwm_counts", "/twin/motor_current")


class LiveRobot:
    """One robot of the live world: its view, namespace, state samples and rows, and the bus
    messages not yet sent."""

    def __init__(self, world, robot, name: str | None = None):
        self.view = view = RobotView(world, robot, name)
        self.namespace = RobotNamespace(view.name)
        model, named = view.observables.model, view.observables.named
        self.state = StateSampler(model, named, prefix=view.prefix)
        world.on_grid(self.state.sample)
        self.state.sample(world.t_phys_us)
        self.rows = LiveRows(view)
        self.bus_out: list[tuple[int, int, str, bytes]] = []  # t_ns, seq, topic, payload


class FleetFoxgloveSink:
    """Serve every robot of ``world`` (a :class:`~amr_twin.assembly.world.World`, built, not yet
    run) live, fed by ``pacer`` (its ``flush`` at each tick); ``urdf`` the robots' description
    (``/<name>/robot_description``); ``host``, ``port`` where to listen (0: a free port);
    ``names`` the robots' namespaces (None: their names in the model)."""

    def __init__(
        self, world, pacer, urdf: str, host: str = "127.0.0.1", port: int = 8765, names=None
    ):
        import foxglove

        self.world, self.pacer, self.urdf = world, pacer, urdf
        names = [None] * len(world.robots) if names is None else list(names)
        self.robots = [LiveRobot(world, robot, n) for robot, n in zip(world.robots, names)]
        self._ctx = foxglove.Context()
        self.channels = {}
        for r in self.robots:
            for topic, typ in live_topics(r.view).items():
                if topic.startswith("/twin/") and topic[6:] in ("collisions", "faults"):
                    continue
                name = r.namespace.topic(topic)
                if name not in self.channels:
                    schema = foxglove.Schema(
                        name=ros2_type(typ), encoding="ros2msg", data=msgdef(typ).encode()
                    )
                    self.channels[name] = foxglove.Channel(
                        name, message_encoding="cdr", schema=schema, context=self._ctx
                    )
        self._latched_due = True
        self._seq = 0
        for r in self.robots:
            r.view.on_message(self._tap_of(r))
        sink = self

        class Listener(foxglove.ServerListener):
            def on_subscribe(self, client, channel) -> None:
                if channel.topic == "/tf_static" or channel.topic.endswith("/robot_description"):
                    try:
                        pacer.post(sink._latch)
                    except RuntimeError:  # the world has stopped
                        pass

        try:
            self.server = foxglove.start_server(
                name="amr-twin fleet",
                host=host,
                port=port,
                context=self._ctx,
                server_listener=Listener(),
                capabilities=[foxglove.Capability.Time],
                supported_encodings=["cdr"],
            )
        except RuntimeError as exc:  # foxglove's FoxgloveError, e.g. the port taken since the check
            raise OSError(f"--port {port}: cannot serve on {host}:{port}: {exc}") from None
        self.host, self.port = host, self.server.port

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def _latch(self) -> None:
        self._latched_due = True

    def _tap_of(self, r: LiveRobot):
        ns, out, channels = r.namespace, r.bus_out, self.channels

        def tap(topic: str, msg, t_us: int) -> None:
            entry = BUS_TOPICS.get(topic)
            if entry is None:
                return
            name = ns.topic(entry[0])
            channel = channels.get(name)
            if channel is None or not channel.has_sinks():
                return
            self._seq += 1
            out.append((t_us * 1000, self._seq, name, entry[2](ns.message(msg))))

        return tap

    def flush(self, t_us: int) -> None:
        """Send everything up to ``t_us`` (simulated), in time order; broadcast the time."""
        t_ns, channels = t_us * 1000, self.channels
        if self._latched_due:
            self._latched_due = False
            channels["/tf_static"].log(
                encode_tf_message(static_transforms(self.robots)), log_time=t_ns
            )
            description = encode_string(String(self.urdf))
            for r in self.robots:
                channels[r.namespace.topic("robot_description")].log(description, log_time=t_ns)
        items = []
        for i, r in enumerate(self.robots):
            items += [(t, 0, s, name, data) for t, s, name, data in r.bus_out]
            r.bus_out.clear()  # the tap holds this list
            batch = r.state.split(t_us)
            if i == 0 and channels["/clock"].has_sinks():
                items += [(t * 1000, 1, 0, "/clock", encode_clock(clock(t))) for t in batch.t_us]
            if batch.t_us:
                items += [
                    (t, 2, k, topic, data)
                    for t, k, topic, _typ, data in _state_items(
                        SimpleNamespace(state=batch), 0, r.namespace
                    )
                    if channels[topic].has_sinks()
                ]
            rows = r.rows.take(t_us)
            if rows is not None:
                items += self._row_items(r, rows)
        items.sort(key=lambda it: (it[0], it[1], it[2]))
        for t, _g, _o, topic, data in items:
            channels[topic].log(data, log_time=t)
        self.server.broadcast_time(t_ns)

    def _row_items(self, r: LiveRobot, rows) -> list:
        """A robot's true wheel speeds, PWM, currents (100 Hz) and battery (10 Hz), as the
        ``.mcap`` holds them, for the channels someone subscribed to."""
        ns, out = r.namespace, []
        t_ns = (rows.t_us * 1000).tolist()
        for name, column in zip(ROW_TOPICS, (rows.true_rpm, rows.pwm_counts, rows.current_a)):
            channel = self.channels[ns.topic(name)]
            if channel.has_sinks():
                out += [
                    (t, 3, i, channel.topic, encode_float64_multi_array(v))
                    for i, (t, v) in enumerate(zip(t_ns, column.tolist()))
                ]
        topic = ns.topic("/battery_state")
        if self.channels[topic].has_sinks():
            cap, frame = r.view.cfg.battery.capacity_ah, ns.frame("base_link")
            volts, amps, soc = (
                rows.battery_v.tolist(),
                rows.battery_a.tolist(),
                rows.battery_soc.tolist(),
            )
            out += [
                (
                    t,
                    3,
                    i,
                    topic,
                    encode_battery_state(t, volts[i], -amps[i], soc[i] * cap, cap, soc[i], frame),
                )
                for i, t in enumerate(t_ns)
                if rows.index[i] % BATTERY_EVERY_ROWS == 0
            ]
        return out

    def close(self) -> None:
        """Stop the server (clients are disconnected)."""
        self.server.stop()
