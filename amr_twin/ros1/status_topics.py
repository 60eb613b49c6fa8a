"""The twin's 100 Hz rows and statuses on the graph, for the bridge: :class:`StatusTopics`.

``/twin/true_rpm``, ``/twin/pwm_counts``, ``/twin/motor_current`` (``std_msgs/Float64MultiArray``,
100 Hz, the recorder's columns: :class:`~amr_twin.ros1.row_feed.RowFeed`, kept from the first flush
that finds one of these topics wanted), ``/battery_state`` (``sensor_msgs/BatteryState``, 10 Hz) and
``/diagnostics`` (``diagnostic_msgs/DiagnosticArray``: each collision and fault as it happens, the
``.mcap``'s ``/twin/collisions`` and ``/twin/faults`` statuses, and the battery once a second),
written into the bridge's outbox with their simulated instants (the rows and the battery a block a
topic and tick: :meth:`~amr_twin.ros1.row_feed.RowFeed.blocks`; ``/diagnostics`` with genpy).
"""

from __future__ import annotations

import io

from amr_twin.ros1.outbox import Outbox
from amr_twin.ros1.row_feed import RowBlocks, RowFeed
from amr_twin.recording.event_log import statuses

ROW_TOPICS = ("/twin/true_rpm", "/twin/pwm_counts", "/twin/motor_current")
DIAGNOSTICS_PERIOD_ROWS = 100
"""The battery's status on /diagnostics every 100th row of the 100 Hz grid (1 Hz)."""


class StatusTopics:
    """The topics of the module notes for ``twin``: ``pub(name, type)`` makes a rospy publisher,
    ``conv`` is the bridge's :class:`~amr_twin.ros1.messages.Ros1Messages`, ``out`` its
    :class:`~amr_twin.ros1.outbox.Outbox`."""

    def __init__(self, twin, conv, out: Outbox, pub):
        self.twin, self.conv, self.out, self.rospy = twin, conv, out, conv.rospy
        self.row_pubs = {t: pub(t.lstrip("/"), "std_msgs/Float64MultiArray") for t in ROW_TOPICS}
        self.battery_pub = pub("battery_state", "sensor_msgs/BatteryState")
        self.diag_pub = pub("diagnostics", "diagnostic_msgs/DiagnosticArray")
        self._rows = None
        self._events_sent: set = set()

    @property
    def publishers(self) -> list:
        return [*self.row_pubs.values(), self.battery_pub, self.diag_pub]

    def collect(self, t_us: int) -> None:
        """The rows and statuses up to ``t_us`` into the outbox."""
        if self._rows is None:
            if any(Outbox.wanted(p) for p in self.publishers):
                self._rows = RowFeed(self.twin)
        else:
            rows = self._rows.blocks(t_us)
            if rows is not None:
                self._publish_rows(rows)
        self._publish_events(t_us)

    def _publish_rows(self, rows: RowBlocks) -> None:
        for topic, block in zip(ROW_TOPICS, (rows.true_rpm, rows.pwm_counts, rows.current_a)):
            pub = self.row_pubs[topic]
            if Outbox.wanted(pub):
                self.out.put_block(pub, rows.t_us, block)
        if Outbox.wanted(self.battery_pub):
            self.out.put_block(self.battery_pub, rows.battery_us, rows.battery)
        if Outbox.wanted(self.diag_pub):
            grid_us = self.twin.grid_us
            for i, t in enumerate(rows.t_us):
                if t // grid_us % DIAGNOSTICS_PERIOD_ROWS:
                    continue
                volts, amps, soc = rows.battery_rows[i].tolist()
                stamp = self.rospy.Time(t // 1_000_000, t % 1_000_000 * 1000)
                self._publish_status(
                    t,
                    stamp,
                    0 if soc > 0.2 else 1,
                    "amr/battery",
                    f"{volts:.2f} V, {soc * 100:.0f} %",
                    {"voltage_v": volts, "current_a": amps, "soc": soc},
                )

    def _publish_events(self, t_us: int) -> None:
        for t_ns, _topic, level, name, message, values in statuses(self.twin):
            key = (t_ns, name)
            if t_ns <= t_us * 1000 and key not in self._events_sent:
                self._events_sent.add(key)
                stamp = self.rospy.Time(t_ns // 1_000_000_000, t_ns % 1_000_000_000)
                self._publish_status(-(-t_ns // 1000), stamp, level, name, message, values)

    def _publish_status(
        self, t_us: int, stamp, level: int, name: str, message: str, values: dict
    ) -> None:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        array = DiagnosticArray(
            status=[
                DiagnosticStatus(
                    level=level,
                    name=name,
                    message=message,
                    hardware_id="amr",
                    values=[KeyValue(str(k), str(v)) for k, v in values.items()],
                )
            ]
        )
        array.header.stamp = stamp
        self.put_ros(self.diag_pub, array, t_us)

    def put_ros(self, pub, msg, t_us: int) -> None:
        """A genpy message into the outbox (the bytes rospy's publish would write)."""
        buf = io.BytesIO()
        msg.serialize(buf)
        self.out.put(pub, buf.getvalue(), t_us)
