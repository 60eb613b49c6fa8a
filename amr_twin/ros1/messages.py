"""The twin's messages as rospy's, and back (the ROS 1 bridge's conversions).

The twin's messages (:mod:`amr_twin.ros.messages`, ``geometry_messages``, ``sensor_messages``) carry
the ROS 1 field names and their ``_type``; :class:`Ros1Messages` fills the rospy class of the same
type field by field, following the class' ``_slot_types`` (a plan kept per class): ``time`` from the
twin's ``Time(sec, nanosec)``, arrays as plain lists (``rospy.numpy_msg`` fails with numpy >= 2.3),
nested messages recursively (the bridge's low-rate and latched messages; the high-rate ones are
written by
:mod:`amr_twin.ros1.serialization`). Incoming ``cmd_vel`` and ``wheel_Command`` come back as the
twin's messages, checked by :mod:`amr_twin.live.inputs` as any client's are.
"""

from __future__ import annotations

from typing import Any, Callable

from amr_twin.live.inputs import InputError, _finite, check_request
from amr_twin.ros.geometry_messages import Twist, Vector3
from amr_twin.ros.messages import Float64MultiArray

PRIMITIVE = {"float64": float, "float32": float, "string": str, "bool": bool}


class Ros1Messages:
    """Converter from the twin's messages to rospy's (:meth:`to_ros`); needs rospy importable."""

    def __init__(self):
        from amr_twin.ros1.installation import import_rospy

        self.rospy = import_rospy()
        import roslib.message

        self._get_class = roslib.message.get_message_class
        self._classes: dict[str, type] = {}
        self._plans: dict[type, list[tuple[str, Callable[[Any], Any]]]] = {}

    def ros_class(self, type_name: str) -> type:
        """The rospy message class of ``pkg/Name`` (ValueError if Debian's packages lack it)."""
        cls = self._classes.get(type_name)
        if cls is None:
            cls = self._get_class(type_name)
            if cls is None:
                raise ValueError(
                    f"no ROS 1 message class {type_name} (install its python3-*-msgs package)"
                )
            self._classes[type_name] = cls
        return cls

    def to_ros(self, msg) -> Any:
        """``msg`` (a twin message with ``_type``) as an instance of its rospy class."""
        cls = self.ros_class(msg._type)
        plan = self._plans.get(type(msg))
        if plan is None:
            plan = self._plans[type(msg)] = [
                (name, self._converter(typ)) for name, typ in zip(cls.__slots__, cls._slot_types)
            ]
        out = cls()
        for name, convert in plan:
            setattr(out, name, convert(getattr(msg, name)))
        return out

    def _converter(self, typ: str) -> Callable[[Any], Any]:
        rospy = self.rospy
        if typ == "time":
            return lambda t: rospy.Time(t.sec, t.nanosec)
        if typ == "duration":
            return lambda t: rospy.Duration(t.sec, t.nanosec)
        if "[" in typ:
            base = typ[: typ.index("[")]
            if "/" in base or base == "Header":
                return lambda values: [self.to_ros(v) for v in values]
            return lambda values: values.tolist() if hasattr(values, "tolist") else list(values)
        if "/" in typ or typ == "Header":
            return self.to_ros
        return PRIMITIVE.get(typ, int)


def twist_from_ros(msg) -> Twist:
    """A rospy ``geometry_msgs/Twist`` as the twin's (m/s, rad/s); InputError if a value is not
    finite."""
    return Twist(
        Vector3(*(_finite(getattr(msg.linear, a), f"linear.{a}") for a in "xyz")),
        Vector3(*(_finite(getattr(msg.angular, a), f"angular.{a}") for a in "xyz")),
    )


def wheel_command_from_ros(msg) -> Float64MultiArray:
    """A rospy ``std_msgs/Float64MultiArray`` on ``wheel_Command`` as the twin's, checked as a
    request ``[motion, RPM, motion, RPM]`` (InputError naming the field otherwise)."""
    req = check_request(list(msg.data))
    return Float64MultiArray(
        data=[float(req.motionL), float(req.speedL), float(req.motionR), float(req.speedR)]
    )


__all__ = ["InputError", "Ros1Messages", "twist_from_ros", "wheel_command_from_ros"]
