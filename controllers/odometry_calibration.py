"""The wheel odometry's calibration file: per-wheel effective radii and the effective wheelbase.

What a UMBmark calibration (Borenstein and Feng, IEEE Trans. Robot. Autom. 12(6), 1996;
``amr-twin experiment umbmark``) gives the odometry node
(:class:`~amr_twin.controllers.odometry.WheelOdometry`): the radii it integrates each wheel's speed
with and the wheelbase it turns the difference into a yaw rate with, in place of the nominal
geometry. The YAML (names in the manner of ROS' diff_drive_controller, SI units)::

    wheel_odometry:
      left_wheel_radius_m: 0.12493
      right_wheel_radius_m: 0.12507
      wheel_separation_m: 0.4861
      source: "amr-twin experiment umbmark, seed 0 (E_d 1.00112, E_b 1.0127)"

``amr-twin run --odometry FILE`` and :class:`~amr_twin.assembly.twin.TwinOptions`
(``odometry_calibration``) take it; :func:`load` refuses a bad file in one line (ValueError),
:func:`text` writes one."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

KEY = "wheel_odometry"
FIELDS = ("left_wheel_radius_m", "right_wheel_radius_m", "wheel_separation_m")
BOUNDS = {
    "left_wheel_radius_m": (0.05, 0.3),
    "right_wheel_radius_m": (0.05, 0.3),
    "wheel_separation_m": (0.2, 1.0),
}
"""Allowed values, m (those of ``wheel.radius_m`` and ``wheel.separation_m`` in the parameter
schema)."""


@dataclass(frozen=True)
class OdometryCalibration:
    """Effective geometry of the wheel odometry, m."""

    left_wheel_radius_m: float
    right_wheel_radius_m: float
    wheel_separation_m: float
    source: str = ""

    def multipliers(self, radius_m: float, separation_m: float) -> dict:
        """The node's keyword arguments that turn the nominal ``radius_m`` / ``separation_m`` into
        these."""
        return {
            "left_radius_multiplier": self.left_wheel_radius_m / radius_m,
            "right_radius_multiplier": self.right_wheel_radius_m / radius_m,
            "wheel_separation_multiplier": self.wheel_separation_m / separation_m,
        }


def load(path: Path | str) -> OdometryCalibration:
    """Read a calibration file; ValueError naming the file and the field otherwise."""
    from amr_twin.model.yaml_file import read_yaml

    path = Path(path)
    if not path.exists():
        raise ValueError(
            f"--odometry {path}: no such file (amr-twin experiment umbmark writes one)"
        )
    data = read_yaml(
        path, "--odometry", ValueError
    )  # a device, a pipe, binary or bad YAML: one line
    node = data.get(KEY) if isinstance(data, dict) else None
    if not isinstance(node, dict):
        raise ValueError(f"--odometry {path}: expected a '{KEY}:' mapping with {', '.join(FIELDS)}")
    unknown = set(node) - set(FIELDS) - {"source"}
    if unknown:
        raise ValueError(
            f"--odometry {path}: {KEY}.{sorted(unknown)[0]}: unknown key (allowed: "
            f"{', '.join(FIELDS)}, source)"
        )
    values = {}
    for name in FIELDS:
        value = node.get(name)
        lo, hi = BOUNDS[name]
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
            or not lo <= value <= hi
        ):
            raise ValueError(
                f"--odometry {path}: {KEY}.{name}: {value!r}, expected a number in [{lo}, {hi}] m"
            )
        values[name] = float(value)
    return OdometryCalibration(**values, source=str(node.get("source", "")))


def text(calibration: OdometryCalibration, comment: str = "") -> str:
    """The YAML of ``calibration`` (``comment``: lines put above it, each behind ``#``)."""
    lines = [f"# {line}" for line in comment.splitlines()]
    lines.append(f"{KEY}:")
    lines += [f"  {name}: {getattr(calibration, name):.6f}" for name in FIELDS]
    lines.append(f"  source: {json.dumps(calibration.source)}")  # a JSON string is a YAML string
    return "\n".join(lines) + "\n"
