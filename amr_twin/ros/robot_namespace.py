"""One robot's ROS namespace in a world of several: :class:`RobotNamespace`.

The multi-robot convention of ROS (REP-105 with one tf tree, as nav2's multi-robot launch and
``robot_state_publisher``'s ``frame_prefix`` give it): each robot's topics under ``/<name>/``
(``/amr-1/odom``, ``/amr-1/scan``), its frames prefixed ``<name>/`` (``amr-1/odom``,
``amr-1/base_link``, ``amr-1/laser``) on the one ``/tf`` and ``/tf_static`` of the world; the
frames the robots share keep their names: ``map`` (the world's map, parent of each robot's
``<name>/odom`` through its localiser), ``world`` (the ground truth's) and the UWB anchors
``uwb_anchor_<i>`` (fixtures of the map). ``/clock`` is the world's, one for all.
"""

from __future__ import annotations

import dataclasses

from amr_twin.ros.messages import Header

SHARED_TOPICS = ("/tf", "/tf_static", "/clock")
"""Topics of the world, one for all robots (not namespaced)."""
SHARED_FRAMES = ("map", "world")
"""Frames every robot of a world shares (not prefixed)."""
SHARED_FRAME_PREFIXES = ("uwb_anchor_",)
"""Frames starting so are fixtures of the map, shared (not prefixed)."""


class RobotNamespace:
    """The namespace of the robot ``name`` (``amr-1``; module notes)."""

    def __init__(self, name: str):
        if not name or "/" in name:
            raise ValueError(f"name {name!r}: a robot's name is one word without '/'")
        self.name = name
        self._prefix = name + "/"

    def topic(self, topic: str) -> str:
        """``/<name>/<topic>`` of a robot's topic (``odom`` or ``/odom``); the world's
        (:data:`SHARED_TOPICS`) as they are."""
        topic = "/" + topic.lstrip("/")
        return topic if topic in SHARED_TOPICS else "/" + self._prefix + topic[1:]

    def frame(self, frame: str) -> str:
        """The robot's frame ``frame`` in the world: ``<name>/<frame>``, the shared frames (and an
        empty one) as they are."""
        if not frame or frame in SHARED_FRAMES or frame.startswith(SHARED_FRAME_PREFIXES):
            return frame
        if frame.startswith(self._prefix):
            return frame
        return self._prefix + frame.lstrip("/")

    def message(self, msg):
        """A copy of ``msg`` (a message dataclass of :mod:`amr_twin.ros`) whose headers'
        ``frame_id`` and ``child_frame_id`` fields, nested ones and those of lists of messages
        included, are the robot's (:meth:`frame`); ``msg`` itself unchanged, arrays shared."""
        if isinstance(msg, Header):
            return dataclasses.replace(msg, frame_id=self.frame(msg.frame_id))
        if not dataclasses.is_dataclass(msg):
            return msg
        changes = {}
        for f in dataclasses.fields(msg):
            value = getattr(msg, f.name)
            if f.name == "child_frame_id" and isinstance(value, str):
                changes[f.name] = self.frame(value)
            elif isinstance(value, Header) or (
                dataclasses.is_dataclass(value) and _has_frames(type(value))
            ):
                changes[f.name] = self.message(value)
            elif isinstance(value, list) and value and dataclasses.is_dataclass(value[0]):
                if _has_frames(type(value[0])):
                    changes[f.name] = [self.message(v) for v in value]
        return dataclasses.replace(msg, **changes) if changes else msg


_FRAMED: dict[type, bool] = {}


def _has_frames(cls: type) -> bool:
    """Whether messages of ``cls`` have a ``header`` or a ``child_frame_id`` field (memoised)."""
    known = _FRAMED.get(cls)
    if known is None:
        names = {f.name for f in dataclasses.fields(cls)}
        known = _FRAMED[cls] = bool(names & {"header", "child_frame_id"})
    return known
