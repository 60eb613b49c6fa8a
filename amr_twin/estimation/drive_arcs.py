"""A differential drive's geometry (:class:`DriveGeometry`) and its pose carried along two wheel
speed profiles in C (:class:`ArcKernel`).

:func:`amr_twin.estimation.dead_reckoning.integrate` is the Python twin of ``drive_arcs.c``: the
same arcs in the same order, the same bits (tests/estimation/test_drive_arcs.py). The wheel
odometry node integrates its smoothed pose at every publish while a speed varies (the start's
ramp: some 25 arcs a call); the C form runs when the body is a :class:`DriveGeometry` and the
helper builds (:mod:`amr_twin.base.native_build`). Measurements: docs/reference/speed.md.
"""

from __future__ import annotations

import ctypes
import math
from array import array
from dataclasses import dataclass
from pathlib import Path

from amr_twin.base.native_build import open_helper

C_SOURCE = Path(__file__).with_name("drive_arcs.c")


@dataclass(frozen=True)
class DriveGeometry:
    """Wheel speeds to the body twist of a differential drive: left and right wheel radius, m,
    and wheel separation, m (all > 0)."""

    left_radius_m: float
    right_radius_m: float
    separation_m: float

    def __call__(self, left_rpm: float, right_rpm: float) -> tuple[float, float]:
        """``(v_m_s, w_rad_s)``: forward speed and yaw rate (CCW +) of signed wheel speeds, RPM."""
        v_left = left_rpm * 2.0 * math.pi / 60.0 * self.left_radius_m
        v_right = right_rpm * 2.0 * math.pi / 60.0 * self.right_radius_m
        return 0.5 * (v_left + v_right), (v_right - v_left) / self.separation_m


class ArcKernel:
    """``dr_integrate`` and ``pp_advance`` of a loaded ``drive_arcs.c`` (:func:`arc_kernel`)."""

    def __init__(self, lib: ctypes.PyDLL):
        fn = self._fn = lib.dr_integrate
        p, i, q, d = ctypes.c_void_p, ctypes.c_int, ctypes.c_int64, ctypes.c_double
        fn.restype, fn.argtypes = i, [p, p, i, p, p, i, q, p, q, q, d, d, d]
        fn = self._advance = lib.pp_advance
        fn.restype, fn.argtypes = i, [p] * 6
        self._pose = (ctypes.c_double * 3)()
        self._pose_at = ctypes.addressof(self._pose)

    def integrate(
        self, profiles, start: tuple, t_end_us: int, max_substep_us: int, body: DriveGeometry
    ) -> tuple:
        """:func:`~amr_twin.estimation.dead_reckoning.integrate` in C: ``(t_end_us, x_m, y_m,
        yaw_rad)`` from ``start`` (``t_us, x_m, y_m, yaw_rad``) along the two
        :class:`~amr_twin.estimation.speed_profile.SpeedProfile` (left, right)."""
        left, right = profiles
        tl, rl = array("q", left.t_us), array("d", left.rpm)
        tr, rr = array("q", right.t_us), array("d", right.rpm)
        pose = self._pose
        pose[0], pose[1], pose[2] = start[1], start[2], start[3]
        done = self._fn(
            tl.buffer_info()[0],
            rl.buffer_info()[0],
            len(tl),
            tr.buffer_info()[0],
            rr.buffer_info()[0],
            len(tr),
            start[0],
            self._pose_at,
            t_end_us,
            max_substep_us,
            body.left_radius_m,
            body.right_radius_m,
            body.separation_m,
        )
        if done < 0:
            raise ValueError(f"integrate: max_substep_us {max_substep_us} must be >= 1")
        return t_end_us, pose[0], pose[1], pose[2]

    def advance(
        self,
        profiles,
        t_us: int,
        now_us: int,
        pose: tuple,
        used: list,
        accel: tuple,
        correction: tuple,
        max_substep_us: int,
        body: DriveGeometry,
    ) -> tuple:
        """The forward integration of
        :meth:`~amr_twin.estimation.published_pose.PublishedPose.advance` in C: the pose
        (``x_m, y_m, yaw_rad``) at ``now_us`` from ``pose`` at ``t_us``; ``used`` (left, right RPM
        the pose moves with) is updated in place. ``accel``: RPM/us; ``correction``: the body twist
        added, m/s, m/s, rad/s."""
        left, right = profiles
        tl, rl = array("q", left.t_us), array("d", left.rpm)
        tr, rr = array("q", right.t_us), array("d", right.rpm)
        ints = array("q", (len(tl), len(tr), t_us, now_us, max_substep_us))
        io = array(
            "d",
            (
                *pose,
                *used,
                *accel,
                *correction,
                body.left_radius_m,
                body.right_radius_m,
                body.separation_m,
            ),
        )
        done = self._advance(
            tl.buffer_info()[0],
            rl.buffer_info()[0],
            tr.buffer_info()[0],
            rr.buffer_info()[0],
            ints.buffer_info()[0],
            io.buffer_info()[0],
        )
        if done < 0:
            raise ValueError(f"advance: max_substep_us {max_substep_us} must be >= 1")
        used[0], used[1] = io[3], io[4]
        return io[0], io[1], io[2]


_kernel: list = []


def arc_kernel() -> ArcKernel | None:
    """The C form of ``integrate`` (built at first use), or None without its helper."""
    if not _kernel:
        lib, _engine = open_helper(C_SOURCE)
        _kernel.append(ArcKernel(lib) if lib is not None else None)
    return _kernel[0]
