"""The navigator's senses and its commands' guards: each scan into the costmap, the people tracker
and the map matcher; each command through the collision monitor and the yielding.

Reasons and measurements: docs/explanation/navigation.md#amr_twinnavigationnavigator."""

from __future__ import annotations

import math

import numpy as np

from amr_twin.navigation.kinematics import to_map
from amr_twin.ros.geometry_messages import Twist, Vector3


class Perception:
    """The scan and command half of :class:`amr_twin.navigation.navigator.Navigator`, which holds
    the bus, the clock, the pose source, the costmap, the tracker, the monitor and the yielding."""

    def _on_scan(self, scan) -> None:
        if not self.pose_source.ready:
            return
        origin, end, hit = self.pose_source.scan_in_map(
            scan, self.p.laser_xy_yaw, self.p.raytrace_range_m
        )
        if self.matcher is not None:
            matches = self.matcher.matches
            step = self.matcher.update(origin[len(origin) // 2], end[hit])
            if step[2] or step[0] or step[1]:
                origin, end = to_map(np.array([step]), origin)[0], to_map(np.array([step]), end)[0]
                self.pose_source.correction = self.matcher.correction
            if (
                self._matched is not None and self.matcher.matches > matches
            ):  # to the EKF, which takes it in
                before = self.pose_source.raw_pose()
                self._matched.publish(
                    self.matcher.pose_message(
                        self.pose_source.pose(), self.pose_source.stamp_s, self.matcher.matches
                    )
                )
                self.pose_source.rebase(before)
                self.matcher.correction = self.pose_source.correction
        self.costmap.update_scan(origin, end, hit, self.p.obstacle_range_m, self.p.raytrace_range_m)
        self._scan_points = end[hit]
        self._unmapped = self.costmap.static_distance_at(self._scan_points) > self.p.unmapped_m
        t = scan.header.stamp.to_sec() + scan.time_increment * np.arange(len(hit))
        person = self._unmapped
        if self.fleet is not None:  # a fleet mate's returns are not a person's
            person = person & ~self.fleet.theirs(self._fleet_index, self._scan_points)
        self.tracker.update(self._scan_points[person], t[hit][person], origin[0], t[-1])
        self.people = self.tracker.people()

    def _publish(self, v: float, w: float) -> None:
        pose = self.pose_source.pose() if self.pose_source.ready else None
        wanted = (v, w)
        if pose is not None and len(self._scan_points) and (v or w):
            v, w = self.monitor.filter(v, w, *self._in_base(pose))
        if self.yielding is not None and pose is not None and not self.done:
            v, w = self._yield(pose, wanted, (v, w))
        self.commands.append((self.clock.now_s, v, w))
        self._cmd.publish(Twist(Vector3(float(v), 0.0, 0.0), Vector3(0.0, 0.0, float(w))))

    def _in_base(self, pose, people: bool = True) -> tuple:
        """What the collision monitor takes, in the base frame: the scan's points (n, 2), which of
        them are unmapped, and (``people``) the people's predicted positions and velocities (or
        None)."""
        c, s = math.cos(pose[2]), math.sin(pose[2])
        rot = np.array([[c, -s], [s, c]])  # map -> base: row vectors times this
        if people and len(self.people):
            xy = (
                self.people.at(np.array([self.clock.now_s]), self.tracker.horizon_s)[:, 0]
                - pose[:2]
            )
            people = (xy @ rot, self.people.v_m_s @ rot)
        else:
            people = None
        return (self._scan_points - pose[:2]) @ rot, self._unmapped, people

    def _yield(self, pose, wanted, filtered) -> tuple[float, float]:
        """``filtered`` or, with a person about to walk into the robot where it would stand, the way
        out of their path (:class:`~amr_twin.navigation.yielding.Yielding`), ramped, through the
        monitor's zones of returns (not its people zones: they would stop the way out)."""
        vel = self._velocity()
        out = self.yielding.command(
            self.clock.now_s, pose, vel, wanted, filtered, self.people, self._scan_points
        )
        if out is None:
            return filtered
        v, w = self.limits.ramp(*out, *vel, self.dt_s)
        if len(self._scan_points) and (v or w):
            v, w = self.monitor.filter(v, w, *self._in_base(pose, people=False))
        return v, w
