"""The robot's courtesy to people standing: it waits before passing close to someone standing beside
its way, and breaks a standoff with someone standing ahead (docs/explanation/actors.md, "The robot
gives way")."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from amr_twin.navigation.people import People


@dataclass
class CourtesyWait:
    """A wait for someone standing beside the way: where they stand (m, ``map``), when the robot
    began to stop for them and when it stood (s; None: not yet)."""

    xy_m: np.ndarray
    began_s: float
    stood_s: float | None = None


class Courtesy:
    """The waits of :class:`amr_twin.navigation.yielding.Yielding`, which holds the settings
    (``courtesy_m``, ``courtesy_s``, ``standoff_m``, ...), the waits and the roll-outs."""

    def _courtesy_wait(self, now_s: float, pose, vel, filtered, people: People) -> bool:
        """Whether to stand rather than pass within ``courtesy_m`` of a standing person's disc (they
        may step out into the robot's way as it passes): the ``filtered`` command held over the
        horizon would, the robot is still coming nearer, and it would cross that line within its
        stopping distance (else it drives on and stops later, at the line); once stopping for
        someone there it stands until it has stood ``courtesy_s``."""
        poses = self._rollout(pose, vel, np.asarray(filtered, float)[None])
        xy = people.xy_m
        gaps = self._signed_m(self._local(poses, np.broadcast_to(xy, poses.shape[:2] + xy.shape)))[
            0
        ]  # (n, N)
        way = gaps.min(0)
        now = self._signed_m(self._local(np.array(pose, float)[None, None], xy[None, None]))[0, 0]
        near = (way - self.person_radius_m < self.courtesy_m) & (now > way + 0.05)
        steps = np.diff(np.vstack([np.asarray(pose, float)[None, :2], poses[0, :, :2]]), axis=0)
        path = np.cumsum(np.hypot(steps[:, 0], steps[:, 1]))  # (n,) along the way, m
        inside = gaps - self.person_radius_m < self.courtesy_m
        reach = np.where(inside.any(0), path[np.argmax(inside, axis=0)], np.inf)
        v = abs(float(vel[0]))
        due = (now - self.person_radius_m < self.courtesy_m) | (
            reach <= v * self.stop_lag_s + v * v / (2.0 * self.limits.decel_m_s2) + v * self.dt_s
        )
        stood = now_s if v < 1e-3 else None
        self._courtesy = [
            c
            for c in self._courtesy
            if now_s - (c.began_s if c.stood_s is None else c.stood_s)
            < self.courtesy_s + self.courtesy_forget_s
        ]
        for j in np.flatnonzero(near):
            seen = [c for c in self._courtesy if np.hypot(*(c.xy_m - xy[j])) < 0.5]
            if not seen:
                if due[j]:
                    self._courtesy.append(CourtesyWait(xy[j].copy(), now_s, stood))
                    return True
                continue
            if seen[0].stood_s is None:
                seen[0].stood_s = stood
                return True
            if now_s - seen[0].stood_s < self.courtesy_s:
                return True
        return False

    def _standoff(self, now_s: float, pose, vel, people: People) -> bool:
        """Whether the robot has stood ``standoff_s`` with a person standing within ``standoff_m``
        ahead of it."""
        c, s = math.cos(pose[2]), math.sin(pose[2])
        d = people.xy_m - np.asarray(pose[:2], float)
        local = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
        near = (self.footprint.distance_m(local) - self.person_radius_m < self.standoff_m) & (
            local[:, 0] > 0.0
        )
        if not near.any() or abs(vel[0]) > 0.02:
            self._standing_since = None
            return False
        if self._standing_since is None:
            self._standing_since = now_s
        if now_s - self._standing_since < self.standoff_s:
            return False
        self._standing_since = None
        return True
