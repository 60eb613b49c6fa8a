"""The twin joins a ROS 1 graph for a run: ``amr-twin run ... --ros1 [--roscore]``, ``amr-twin
client --ros1``.

:class:`Ros1Options` is checked before anything is built: Debian's ROS 1 is there (else one line
naming the packages) and, unless ``--roscore`` asks for a private master, the master at
``ROS_MASTER_URI`` answers within 3 s (else one line naming it). :class:`Ros1Session` then starts
the private ``roscore`` (on a free port; its URI is printed), joins the master as the node
``/amr_twin``, sets ``/use_sim_time`` and ``/robot_description``, and bridges the twin
(:class:`~amr_twin.ros1.bridge.Ros1Bridge`), fed by a :class:`~amr_twin.live.pacer.Pacer` (as fast
as possible, or ``--rate`` x real time). Before the twin runs it waits until the nodes already on
the graph (a ``rosbag record``, a node waiting for ``/scan``, the thesis' service publishing
``/wheel_Command``: those the master lists) are connected to it, at most :data:`SETTLE_MAX_S`: a
twin far faster than real time would otherwise run past the first messages before they connect.
:meth:`Ros1Session.close` stops the bridge, rospy and the private roscore.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass

from amr_twin.ros1 import remapping
from amr_twin.ros1.master import DEFAULT_MASTER_URI, Master, master_problem, start_roscore
from amr_twin.ros1.master_watch import MasterWatch
from amr_twin.ros1.node_shutdown import shut_down
from amr_twin.ros1.sim_services import SimServices

NODE_NAME = "amr_twin"
"""The node's name (``__name:=`` renames it), in ``ROS_NAMESPACE`` (or ``__ns:=``) as every relative
name."""
_ABSENT = object()
SETTLE_MAX_S = 10.0
"""Longest wait for the graph's subscribers to connect before the twin runs, wall s (it ends as soon
as they are: a few ms each; the bound only matters for a node the master lists that does not answer,
or a machine so busy that connecting takes seconds, where 2 s was too short)."""
UNPACED_TICK_US = 400_000
"""The pacer's tick when the twin runs unpaced on the graph, us. Each tick stops the physics' grid
loop and costs numpy's work on the state samples and a write per topic and subscriber, whatever
their number (20 ms ticks cost 12 % of the twin's CPU without a subscriber; per tick, ~0.5 ms of the
bridge's CPU and a write per topic and subscriber: docs/how-to/ros1.md); unpaced, nothing waits on
the wall clock. A message from the graph acts at the next tick (400 ms of simulated time, ~8 ms of
wall time at full speed)."""


def pacer_tick_us(rate: float) -> int:
    """The pacer's tick for a bridged twin paced at ``rate`` (0: unpaced), us."""
    from amr_twin.live.pacer import TICK_US

    return TICK_US if rate > 0 else UNPACED_TICK_US


def master_uri() -> str:
    """``ROS_MASTER_URI``, or ROS 1's default."""
    return os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI


def _leave_own_clock(rospy) -> None:
    """The twin is the graph's clock: where ``/use_sim_time`` was already set, rospy subscribed the
    node to ``/clock`` when it joined, and every clock message the twin wrote came back to its own
    process to be read and decoded by rospy's thread (~27 us of CPU each). Unsubscribe it; rospy's
    time in the twin's process stays where it was (its own stamps come from the simulation)."""
    import rospy.impl.simtime as simtime

    sub = getattr(simtime, "_clock_sub", None)
    if sub is not None:
        sub.unregister()
        simtime._clock_sub = None


@dataclass(frozen=True)
class Ros1Options:
    """``--ros1``: join the graph at ``ROS_MASTER_URI``, or a private roscore (``roscore``);
    ``firmware_topics`` False when the board's serial port is served to a rosserial host (it carries
    them)."""

    roscore: bool = False
    firmware_topics: bool = True

    def check(self) -> None:
        """Raise ValueError (one line) when ROS 1 is absent or the master does not answer within 3
        s."""
        from amr_twin.ros1.installation import missing

        problem = missing()
        if problem:
            raise ValueError(f"--ros1: {problem}")
        if not self.roscore:
            problem = master_problem(master_uri(), 3.0)
            if problem:
                raise ValueError(
                    f"--ros1: {problem} (start roscore, or give --roscore for a private one)"
                )


class Ros1Session:
    """Bridge ``twin`` to the ROS 1 graph, fed by ``pacer``; :meth:`close` when the run is over."""

    def __init__(self, twin, pacer, options: Ros1Options, say=print):
        from amr_twin.ros1.bridge import Ros1Bridge
        from amr_twin.ros1.installation import import_rospy

        self.master = start_roscore() if options.roscore else Master(master_uri())
        self.rospy = rospy = None
        try:
            if options.roscore:
                os.environ["ROS_MASTER_URI"] = self.master.uri
                os.environ.setdefault("ROS_IP", "127.0.0.1")
            rospy = self.rospy = import_rospy()
            rospy.init_node(
                NODE_NAME,
                argv=remapping.node_argv(),
                anonymous=False,
                disable_signals=True,
                log_level=rospy.WARN,
            )
            _leave_own_clock(rospy)
            self._sim_time_before = rospy.get_param("/use_sim_time", _ABSENT)
            rospy.set_param("/use_sim_time", True)
            rospy.set_param("robot_description", twin.urdf)
            self.bridge = Ros1Bridge(twin, pacer, firmware_topics=options.firmware_topics)
            self.services = SimServices(twin, pacer, rospy)
        except BaseException:
            if rospy is not None:
                shut_down(rospy, "the twin could not join the graph")
            self.master.stop()
            raise
        pacer.sinks.append(self.bridge)
        self._say = say
        self.watch = MasterWatch(
            self.master.uri,
            rospy,
            {"/use_sim_time": True, rospy.resolve_name("robot_description"): twin.urdf},
            say,
        )
        where = (
            f"a private roscore at {self.master.uri}"
            if options.roscore
            else f"the master at {self.master.uri}"
        )
        say(
            f"ros1: the twin is {rospy.get_name()} on {where} (/use_sim_time, /clock; publish "
            f"{rospy.resolve_name('wheel_Command')} or {rospy.resolve_name('cmd_vel')} to drive "
            f"it; "
            f"{rospy.get_name()}/pause_physics, ...)"
        )
        if not self.settle():
            say(
                f"ros1: not every node the master lists on the twin's topics connected within "
                f"{SETTLE_MAX_S:g} s; "
                "the run starts without them"
            )
        self.bridge.start()

    def _publishers(self) -> list:
        b = self.bridge
        return [
            *b.pubs.values(),
            b.clock_pub,
            *b.state_pubs.values(),
            *b.status.publishers,
            b.description_pub,
        ]

    def settle(self, max_s: float = SETTLE_MAX_S) -> bool:
        """Wait until the twin is connected to each subscriber of its topics and each publisher of
        its inputs that the master lists (at most ``max_s``); True if it is."""
        import rosgraph

        me = self.rospy.get_name()
        pubs, subs, _services = rosgraph.Master(me).getSystemState()
        others = {topic: sum(1 for node in nodes if node != me) for topic, nodes in subs}
        sources = {topic: sum(1 for node in nodes if node != me) for topic, nodes in pubs}
        deadline = time.monotonic() + max_s
        while True:
            if all(
                p.get_num_connections() >= others.get(p.resolved_name, 0)
                for p in self._publishers()
            ) and all(
                s.get_num_connections() >= sources.get(s.resolved_name, 0)
                for s in self.bridge._subs
            ):
                return True
            if time.monotonic() > deadline:
                return False
            time.sleep(0.02)

    def close(self) -> None:
        """Stop the master's watch, the bridge (if the pacer has not) and the services, put
        ``/use_sim_time`` back as it was (deleted if it was not set), stop rospy and wait for its
        server threads (:func:`~amr_twin.ros1.node_shutdown.shut_down`), then the private
        roscore."""
        try:
            self.watch.close()
            self.services.close()
            self.bridge.close()
            if not self.watch.lost:
                self._restore_sim_time()
        finally:
            left = shut_down(self.rospy, "the twin's run is over")
            if left:
                self._say(f"ros1: rospy's server threads {', '.join(left)} did not end")
            self.master.stop()

    def _restore_sim_time(self) -> None:
        try:
            if self._sim_time_before is _ABSENT:
                self.rospy.delete_param("/use_sim_time")
            else:
                self.rospy.set_param("/use_sim_time", self._sim_time_before)
        except (KeyError, OSError):  # deleted meanwhile, or the master gone
            pass
