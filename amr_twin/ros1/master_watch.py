"""The twin's node across a master's loss and restart: :class:`MasterWatch`.

ROS 1 client libraries register with the master once: after a master restart the new master knows
none of the twin's topics, services and parameters, and a node started then finds none of them. The
watch asks the master its pid every :data:`PERIOD_S` (``getPid``, bounded). When none answers it
says so in one line and the twin simulates on (the connections already made are peer to peer: its
subscribers keep receiving); when a master answers again (or one with another pid: a restart between
two looks) it registers every publisher, subscriber and service of the node again (rospy's own
lists, so also those of nodes sharing the process), hands each subscription the publishers the
master lists, sets the parameters again (``/use_sim_time``, ``robot_description``) and says so in
one line."""

from __future__ import annotations

import threading
import xmlrpc.client

from amr_twin.ros1.master import _TimeoutTransport, master_pid

PERIOD_S = 1.0
"""How often the master is asked its pid, wall s (the longest a restart goes unnoticed)."""
TIMEOUT_S = 2.0
"""Bound on each call to the master, wall s."""


class _Closed(Exception):
    """The watch was closed while it registered the node again."""


class MasterWatch:
    """Watch the master at ``uri`` for the node rospy runs; ``params`` (resolved name -> value) are
    set again with the registrations; ``say`` prints one line at a loss and at each registration."""

    def __init__(self, uri: str, rospy, params: dict, say=print, period_s: float = PERIOD_S):
        self.uri, self.rospy, self.params, self.say, self.period_s = (
            uri,
            rospy,
            dict(params),
            say,
            period_s,
        )
        self.pid = master_pid(uri, TIMEOUT_S)
        self.lost = False
        self.losses = 0
        """Times the master stopped answering."""
        self.registrations = 0
        """Times the node registered again."""
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, name="amr_twin master watch", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._done.wait(self.period_s):
            pid = master_pid(self.uri, TIMEOUT_S)
            if pid is None:
                if not self.lost:
                    self.lost, self.losses = True, self.losses + 1
                    self.say(
                        f"ros1: the ROS master at {self.uri} does not answer: the twin simulates "
                        f"on (its "
                        "subscribers stay connected) and registers again when a master answers "
                        "there"
                    )
                continue
            if self.lost or pid != self.pid:
                try:
                    counts = self.register()
                except _Closed:
                    return
                except (OSError, xmlrpc.client.Error):
                    continue  # the master is still starting: the next look tries again
                self.pid, self.lost, self.registrations = pid, False, self.registrations + 1
                self.say(
                    f"ros1: registered again with the ROS master at {self.uri} (pid {pid}): "
                    f"{counts[0]} publishers, {counts[1]} subscribers, {counts[2]} services"
                )

    def register(self) -> tuple[int, int, int]:
        """Register the node's publishers, subscribers and services and set the parameters; their
        counts."""
        from rospy.impl.registration import get_service_manager, get_topic_manager

        rospy = self.rospy
        master = xmlrpc.client.ServerProxy(self.uri, transport=_TimeoutTransport(TIMEOUT_S))
        me, api = rospy.get_name(), rospy.core.get_node_uri()
        node = xmlrpc.client.ServerProxy(api, transport=_TimeoutTransport(TIMEOUT_S))
        for key, value in self.params.items():
            self._go_on()
            master.setParam(me, key, value)
        topics = get_topic_manager()
        pubs, subs, services = (
            topics.get_publications(),
            topics.get_subscriptions(),
            get_service_manager().get_services(),
        )
        for name, data_type in pubs:
            self._go_on()
            master.registerPublisher(me, name, data_type, api)
        for name, data_type in subs:
            self._go_on()
            code, _msg, uris = master.registerSubscriber(me, name, data_type, api)
            if code == 1 and uris:
                self._go_on()
                node.publisherUpdate("/master", name, uris)
        for name, service_api in services:
            self._go_on()
            master.registerService(me, name, service_api, api)
        return len(pubs), len(subs), len(services)

    def _go_on(self) -> None:
        if self._done.is_set():
            raise _Closed

    def close(self) -> None:
        """Stop watching: wait for the thread, at most one call to the master (``TIMEOUT_S``) and a
        second."""
        self._done.set()
        self._thread.join(timeout=TIMEOUT_S + 1.0)
