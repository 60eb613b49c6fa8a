"""Debian's ROS 1 for the ROS 1 path: the packages it needs, whether they are there, rospy's import
path.

rospy and the message packages live in ``/usr/lib/python3/dist-packages`` (Debian's Python 3.11).
The project's venv reaches them by *appending* that folder to ``sys.path`` (:func:`import_rospy`),
so that the venv's numpy and mujoco keep precedence; only the ROS 1 bridge calls it, so no command
that does not use ROS 1 imports it. The package list is ``controllers/ros/debian-packages.txt``,
which ``controllers/ros/install.sh`` (and CI) install.
"""

from __future__ import annotations

import importlib.util
import shutil
import sys
from pathlib import Path

DIST_PACKAGES = "/usr/lib/python3/dist-packages"
PYTHON_MODULES = (
    "rospy",
    "rosgraph",
    "rosbag",
    "std_msgs",
    "std_srvs",
    "sensor_msgs",
    "nav_msgs",
    "geometry_msgs",
    "tf2_msgs",
    "rosgraph_msgs",
    "diagnostic_msgs",
)
"""The Python packages of Debian's ROS 1 the bridge imports."""
TOOLS = ("roscore", "rosmaster")


def ros_folder() -> Path:
    """``controllers/ros``: the catkin workspace's sources, its build and install scripts."""
    spec = importlib.util.find_spec("amr_twin.controllers")
    return Path(list(spec.submodule_search_locations)[0]) / "ros"


def debian_packages() -> list[str]:
    """The Debian packages of the ROS 1 path (``controllers/ros/debian-packages.txt``)."""
    lines = (ros_folder() / "debian-packages.txt").read_text().splitlines()
    return [ln.strip() for ln in lines if ln.strip() and not ln.startswith("#")]


def missing() -> str | None:
    """One line naming what is missing of Debian's ROS 1 and how to install it; None when it is all
    there."""
    absent = [t for t in TOOLS if shutil.which(t) is None]
    absent += [m for m in PYTHON_MODULES if not (Path(DIST_PACKAGES) / m).is_dir()]
    if not absent:
        return None
    return (
        f"ROS 1 is not installed ({', '.join(absent)} missing): install Debian's packages "
        f"{' '.join(debian_packages())} (bash {ros_folder() / 'install.sh'})"
    )


def import_rospy():
    """rospy, from Debian's dist-packages appended to ``sys.path`` (ImportError if absent)."""
    if DIST_PACKAGES not in sys.path:
        sys.path.append(DIST_PACKAGES)
    import rospy

    return rospy
