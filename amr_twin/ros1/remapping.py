"""ROS 1 command-line arguments of the twin's process: ``name:=value`` remaps and ``__name``,
``__ns``, ``__log``, ...

roslaunch starts a ``<node>`` as ``amr-twin ARGS __name:=NAME __log:=FILE`` (with its remaps as
``from:=to`` and ``ns=`` as ``ROS_NAMESPACE``). :func:`split` takes every argument holding ``:=``
out of the command line before typer parses it (rospy's ``myargv`` does the same) and :func:`keep`
remembers them for the node: ``__master``, ``__ip``, ``__hostname`` and ``__ns`` act as
``ROS_MASTER_URI``, ``ROS_IP``, ``ROS_HOSTNAME`` and ``ROS_NAMESPACE`` (set in the environment now,
before the master is checked and rospy imported); the rest go to ``rospy.init_node(argv=...)``
(:func:`node_argv`): ``__name``, ``__log``, remaps, ``_param:=value``."""

from __future__ import annotations

import os
import re

REMAP = ":="
ENVIRONMENT = {
    "__master": "ROS_MASTER_URI",
    "__ip": "ROS_IP",
    "__hostname": "ROS_HOSTNAME",
    "__ns": "ROS_NAMESPACE",
}
"""The special keys that ROS 1 client libraries read as these environment variables."""
_NAME = re.compile(r"^(~|/)?[A-Za-z_][\w/]*$")

_kept: list[str] = []


def split(argv: list[str]) -> tuple[list[str], list[str]]:
    """``(plain, ros)``: the arguments without ``:=`` and those with it, each in its order."""
    ros = [a for a in argv if REMAP in a]
    return [a for a in argv if REMAP not in a], ros


def problem(arg: str) -> str | None:
    """Why ``arg`` is no ROS argument (None: it is one): ``NAME:=VALUE`` with a legal name, a
    value."""
    name, _sep, value = arg.partition(REMAP)
    if not _NAME.match(name) or not value:
        return (
            f"ROS argument {arg!r}: expected NAME:=VALUE (a remap from:=to, __name:=, __ns:=, "
            f"__log:=, "
            "__master:=, __ip:=, __hostname:= or _param:=value)"
        )
    if name == "__name" and not re.match(r"^[A-Za-z][\w]*$", value):
        return (
            f"ROS argument {arg!r}: a node name is a letter then letters, digits or _ (no "
            f"namespace)"
        )
    return None


def keep(ros_args: list[str]) -> None:
    """Remember ``ros_args`` for the node; the special keys of :data:`ENVIRONMENT` go to the
    environment."""
    _kept[:] = ros_args
    for arg in ros_args:
        name, _sep, value = arg.partition(REMAP)
        if name in ENVIRONMENT:
            os.environ[ENVIRONMENT[name]] = value


def kept() -> list[str]:
    """The ROS arguments of this process' command line (:func:`keep`)."""
    return list(_kept)


def node_argv(program: str = "amr-twin") -> list[str]:
    """The ``argv`` for ``rospy.init_node``: the program, then the kept ROS arguments."""
    return [program, *_kept]
