"""ROS 1 message types used by the twin, as plain slotted dataclasses.

Names, field names and field order follow the ROS message definitions. Each class
has a ``_type`` (``"package/Name"``) and ``serialized_size()``, the byte count of
its ROS 1 serialisation (strings and variable arrays prefixed by a uint32 length),
which the rosserial link turns into UART time. Stamps are :class:`Time`
``(sec, nanosec)`` of simulation time, exact from the clock's microseconds
(:meth:`Time.from_us`; ROS 1 names the fields ``secs``/``nsecs``). Covariances are
float64 arrays (row-major 6x6 or 3x3), ``LaserScan`` ranges/intensities float32
arrays; classes holding arrays compare by identity (``eq=False``).

This module holds the stamp, the size helpers and the std_msgs and rosgraph_msgs types;
geometry_msgs, tf2_msgs and nav_msgs are in :mod:`amr_twin.ros.geometry_messages`,
sensor_msgs in :mod:`amr_twin.ros.sensor_messages`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np


def _string_size(text: str) -> int:
    """Serialised size of a ROS string: uint32 length + UTF-8 bytes."""
    return 4 + len(text.encode("utf-8"))


class _Fixed:
    """Base of the message types whose serialisation has a fixed size ``_SIZE``."""

    __slots__ = ()
    _SIZE: ClassVar[int] = 0

    def serialized_size(self) -> int:
        return self._SIZE


def _zeros(n: int):
    return lambda: np.zeros(n, dtype=np.float64)


@dataclass(slots=True, frozen=True)
class Time:
    """A ROS time stamp: whole seconds and nanoseconds (0 <= nanosec < 1e9)."""

    sec: int = 0
    nanosec: int = 0

    @classmethod
    def from_us(cls, t_us: int) -> Time:
        """Exact stamp of an integer number of microseconds.

        Made through the slots directly (a frozen dataclass's ``__init__`` sets each field
        with ``object.__setattr__``: twice the cost); every published message is stamped."""
        sec, rem_us = divmod(int(t_us), 1_000_000)
        if cls is not Time:
            return cls(sec, rem_us * 1000)
        stamp = _new_object(Time)
        _set_sec(stamp, sec)
        _set_nanosec(stamp, rem_us * 1000)
        return stamp

    @classmethod
    def from_sec(cls, t_s: float) -> Time:
        """Stamp of a time in seconds, rounded to the nearest nanosecond."""
        sec, nanosec = divmod(int(round(t_s * 1e9)), 1_000_000_000)
        return cls(sec, nanosec)

    def to_sec(self) -> float:
        """Time in seconds."""
        return self.sec + self.nanosec * 1e-9

    def to_us(self) -> int:
        """Time in whole microseconds (truncated)."""
        return self.sec * 1_000_000 + self.nanosec // 1000


_new_object = object.__new__
_set_sec, _set_nanosec = Time.__dict__["sec"].__set__, Time.__dict__["nanosec"].__set__


# -- std_msgs -----------------------------------------------------------------
@dataclass(slots=True)
class Header:
    """std_msgs/Header: sequence number, stamp (sim time), coordinate frame."""

    _type: ClassVar[str] = "std_msgs/Header"
    seq: int = 0
    stamp: Time = field(default_factory=Time)
    frame_id: str = ""

    def serialized_size(self) -> int:
        return 4 + 8 + _string_size(self.frame_id)


@dataclass(slots=True)
class Float64(_Fixed):
    """std_msgs/Float64."""

    _type: ClassVar[str] = "std_msgs/Float64"
    _SIZE: ClassVar[int] = 8
    data: float = 0.0


@dataclass(slots=True)
class MultiArrayDimension:
    """std_msgs/MultiArrayDimension."""

    _type: ClassVar[str] = "std_msgs/MultiArrayDimension"
    label: str = ""
    size: int = 0
    stride: int = 0

    def serialized_size(self) -> int:
        return _string_size(self.label) + 8


@dataclass(slots=True)
class MultiArrayLayout:
    """std_msgs/MultiArrayLayout (the thesis leaves ``dim`` empty, fig. 3.3)."""

    _type: ClassVar[str] = "std_msgs/MultiArrayLayout"
    dim: list[MultiArrayDimension] = field(default_factory=list)
    data_offset: int = 0

    def serialized_size(self) -> int:
        return 4 + sum(d.serialized_size() for d in self.dim) + 4


@dataclass(slots=True)
class Float64MultiArray:
    """std_msgs/Float64MultiArray."""

    _type: ClassVar[str] = "std_msgs/Float64MultiArray"
    layout: MultiArrayLayout = field(default_factory=MultiArrayLayout)
    data: list[float] = field(default_factory=list)

    def serialized_size(self) -> int:
        return self.layout.serialized_size() + 4 + 8 * len(self.data)


@dataclass(slots=True)
class String:
    """std_msgs/String."""

    _type: ClassVar[str] = "std_msgs/String"
    data: str = ""

    def serialized_size(self) -> int:
        return _string_size(self.data)


@dataclass(slots=True)
class Clock(_Fixed):
    """rosgraph_msgs/Clock: the simulation time (``/clock``, ``use_sim_time``)."""

    _type: ClassVar[str] = "rosgraph_msgs/Clock"
    _SIZE: ClassVar[int] = 8
    clock: Time = field(default_factory=Time)
