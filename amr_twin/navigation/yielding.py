"""The robot gives way to people: it keeps out of their predicted paths, clears the lane of someone
who stopped for it, and waits before passing close to someone standing beside its way
(docs/explanation/actors.md, "The robot gives way").

Social navigation's yield, reconstructed as a last word on ``cmd_vel`` after the collision monitor;
the people are :class:`~amr_twin.navigation.people.People`, the footprint a
:class:`~amr_twin.navigation.footprint.Footprint`, the limits
:class:`~amr_twin.navigation.kinematics.Limits`."""

from __future__ import annotations

import math

import numpy as np

from amr_twin.navigation.courtesy import Courtesy, CourtesyWait
from amr_twin.navigation.people import People


class Yielding(Courtesy):
    """Keeps the robot out of people's predicted paths: social navigation's yield, as a last word on
    ``cmd_vel``.

    Each control cycle (:meth:`command`) the command about to be driven is rolled out over
    ``horizon_s`` with every tracked person walking on (:meth:`People.at`). If a walking person
    would come within ``stop_m`` of the footprint, constant commands of a small grid
    (``speeds_m_s`` x ``turns_rad_s``) are rolled out the same way and the one keeping the largest
    least gap to every person wins (the nearest to the controller's command among equals). People
    who stopped for the robot, standoffs and courtesy stops:
    docs/explanation/navigation.md#amr_twinnavigationyieldingyielding.
    """

    def __init__(
        self,
        footprint,
        limits,
        dt_s: float,
        *,
        person_radius_m: float = 0.25,
        stop_m: float = 0.3,
        margin_m: float = 0.3,
        horizon_s: float = 2.5,
        step_s: float = 0.1,
        pad_m: float = 0.05,
        min_speed_m_s: float = 0.25,
        speeds_m_s: tuple = (-0.25, -0.12, 0.0, 0.15, 0.3, 0.5),
        turns_rad_s: tuple = (-0.6, -0.3, 0.0, 0.3, 0.6),
        standoff_m: float = 0.8,
        standoff_s: float = 3.0,
        back_s: float = 2.0,
        courtesy_m: float = 0.8,
        courtesy_s: float = 3.0,
        courtesy_forget_s: float = 30.0,
        stop_lag_s: float = 0.0,
    ):
        self.footprint, self.limits, self.dt_s = footprint, limits, dt_s
        self.person_radius_m, self.stop_m, self.margin_m = person_radius_m, stop_m, margin_m
        self.n = max(1, int(round(horizon_s / step_s)))
        self.step_s, self.pad_m, self.min_speed_m_s = step_s, pad_m, min_speed_m_s
        v, w = np.meshgrid(np.asarray(speeds_m_s, float), np.asarray(turns_rad_s, float))
        self._grid = np.column_stack([v.ravel(), w.ravel()])
        self.standoff_m, self.standoff_s, self.back_s = standoff_m, standoff_s, back_s
        self.courtesy_m, self.courtesy_s, self.courtesy_forget_s = (
            courtesy_m,
            courtesy_s,
            courtesy_forget_s,
        )
        self.stop_lag_s = stop_lag_s
        self._courtesy: list[CourtesyWait] = []
        """The waits for someone standing: ``courtesy_s`` after the robot stood it passes,
        ``courtesy_forget_s`` later the place is forgotten."""
        self._standing_since: float | None = None
        self._back_until = -np.inf
        self.yields = 0
        """Control cycles whose command was replaced."""

    def _rollout(self, pose, vel, cmds: np.ndarray) -> np.ndarray:
        """Poses (C, n, 3) in ``map`` of constant commands ``cmds`` (C, 2) from ``pose`` at ``vel``,
        ramped."""
        lim, dt = self.limits, self.step_s
        c = len(cmds)
        v, w = np.full(c, float(vel[0])), np.full(c, float(vel[1]))
        x, y, yaw = (
            np.full(c, float(pose[0])),
            np.full(c, float(pose[1])),
            np.full(c, float(pose[2])),
        )
        out = np.empty((c, self.n, 3))
        for k in range(self.n):
            slowing = np.abs(cmds[:, 0]) < np.abs(v)
            dv = np.where(slowing, lim.decel_m_s2, lim.accel_m_s2) * dt
            v = v + np.clip(cmds[:, 0] - v, -dv, dv)
            w = w + np.clip(
                cmds[:, 1] - w, -lim.angular_accel_rad_s2 * dt, lim.angular_accel_rad_s2 * dt
            )
            yaw = yaw + w * dt
            x, y = x + v * dt * np.cos(yaw), y + v * dt * np.sin(yaw)
            out[:, k, 0], out[:, k, 1], out[:, k, 2] = x, y, yaw
        return out

    def _local(self, poses: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """Points ``xy`` (C, n, M, 2) in the frame of each pose (C, n, 3)."""
        c, s = np.cos(poses[..., 2])[..., None], np.sin(poses[..., 2])[..., None]
        dx, dy = xy[..., 0] - poses[..., 0:1], xy[..., 1] - poses[..., 1:2]
        return np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1)

    def _gaps(self, poses: np.ndarray, people: People, now_s: float) -> np.ndarray:
        """Least gap (C, n) from the footprint at each pose to the people walking on, m: negative
        inside it, the deeper the centre the more (a person walking through the robot's middle is
        worse than past its edge)."""
        t = now_s + self.step_s * np.arange(1, self.n + 1)
        future = people.at(t, self.n * self.step_s).transpose(1, 0, 2)  # (n, N, 2)
        local = self._local(poses, np.broadcast_to(future, poses.shape[:2] + future.shape[1:]))
        return self._signed_m(local).min(-1) - self.person_radius_m

    def _signed_m(self, local: np.ndarray) -> np.ndarray:
        """Distance (...) of points ``local`` (..., 2) in ``base_link`` to the footprint, minus
        their depth inside."""
        xy = local.reshape(-1, 2)
        fp = self.footprint
        depth = np.minimum(
            np.minimum(xy[:, 0] - fp.x_min_m, fp.x_max_m - xy[:, 0]),
            fp.half_width_m - np.abs(xy[:, 1]),
        )
        return np.where(depth > 0.0, -depth, fp.distance_m(xy)).reshape(local.shape[:-1])

    def _lane_gaps(self, poses: np.ndarray, people: People) -> np.ndarray:
        """Gap (C,) from the footprint at each roll-out's last pose (C, n, 3) to the lanes of
        ``people`` (their way ahead over the horizon, 0.1 m apart), m: where someone waiting for the
        robot is about to walk."""
        if len(people) == 0:
            return np.full(len(poses), np.inf)
        way = np.arange(0.0, self.n * self.step_s + 1e-9, 0.1)
        lane = (people.xy_m[:, None, :] + people.v_m_s[:, None, :] * way[None, :, None]).reshape(
            -1, 2
        )
        last = poses[:, -1:, :]
        local = self._local(last, np.broadcast_to(lane, (len(poses), 1) + lane.shape))
        return self._signed_m(local).min(-1)[:, 0] - self.person_radius_m

    def _waiting(self, pose, people: People) -> np.ndarray:
        """Which of ``people`` (N,) stand within ``standoff_m`` of the footprint, their last walking
        velocity pointing at the robot: someone who stopped for it and walks on once it is out of
        their way."""
        if people.intent_m_s is None:
            return np.zeros(len(people), bool)
        intent = people.intent_m_s
        standing = np.hypot(*people.v_m_s.T) < self.min_speed_m_s
        c, s = math.cos(pose[2]), math.sin(pose[2])
        d = people.xy_m - np.asarray(pose[:2], float)
        local = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
        near = self.footprint.distance_m(local) - self.person_radius_m < self.standoff_m
        towards = (intent * d).sum(1) < 0.0
        return standing & near & towards & (np.hypot(*intent.T) >= self.min_speed_m_s)

    def _blocked(self, poses: np.ndarray, points_xy_m: np.ndarray, people: People) -> np.ndarray:
        """(C, n) bool: from this step on the footprint grown by ``pad_m`` has reached a return no
        person's."""
        if len(points_xy_m) and len(people):
            near = np.hypot(*(points_xy_m[:, None, :] - people.xy_m[None]).transpose(2, 0, 1)).min(
                1
            )
            points_xy_m = points_xy_m[near > self.person_radius_m + 0.1]
        if len(points_xy_m) == 0:
            return np.zeros(poses.shape[:2], bool)
        reach = self.footprint.circumscribed_radius_m + self.pad_m + 1.0
        start = poses[0, 0, :2]
        points_xy_m = points_xy_m[
            np.hypot(*(points_xy_m - start).T) <= reach + self.n * self.step_s * 0.8
        ]
        if len(points_xy_m) == 0:
            return np.zeros(poses.shape[:2], bool)
        local = self._local(
            poses, np.broadcast_to(points_xy_m, poses.shape[:2] + points_xy_m.shape)
        )
        hit = (
            self.footprint.padded(self.pad_m)
            .contains(local.reshape(-1, 2))
            .reshape(local.shape[:-1])
            .any(-1)
        )
        return np.maximum.accumulate(hit, axis=1)

    def command(
        self, now_s: float, pose, vel, wanted, filtered, people: People, points_xy_m: np.ndarray
    ):
        """The command to drive instead of ``filtered`` (the monitor's ``(v, w)``; ``wanted`` the
        controller's), or None to drive it: ``pose`` (x_m, y_m, yaw_rad) and returns ``points_xy_m``
        (P, 2) in ``map``, ``vel`` the last command."""
        if len(people) == 0:
            self._standing_since = None
            return None
        waiting = self._waiting(pose, people)
        walking = (np.hypot(*people.v_m_s.T) >= self.min_speed_m_s) & ~waiting
        grid = self._grid
        backing = now_s < self._back_until
        if (
            not backing
            and not walking.any()
            and not waiting.any()
            and self._courtesy_wait(now_s, pose, vel, filtered, people)
        ):
            self._standing_since = None  # waiting by choice, not a standoff
            self.yields += 1
            return 0.0, 0.0
        if not backing and not walking.any() and not waiting.any():
            if not self._standoff(now_s, pose, vel, people):
                return None
            self._back_until, backing = now_s + self.back_s, True
        if backing:  # back off, straight when that is as good
            cmds, wanted = (
                np.vstack([[0.0, 0.0], grid[grid[:, 0] < 0.0]]),
                (self.limits.min_v_m_s, 0.0),
            )
        else:
            cmds = np.vstack([np.asarray(filtered, float)[None], grid])
        poses = self._rollout(pose, vel, cmds)
        blocked = self._blocked(poses, np.asarray(points_xy_m, float).reshape(-1, 2), people)
        stuck, k = poses.copy(), np.argmax(blocked, axis=1)
        for i in np.flatnonzero(blocked.any(1)):  # a blocked roll-out stands where it was cut
            stuck[i, k[i] :] = poses[i, k[i] - 1] if k[i] > 0 else np.array(pose, float)
        others = People(people.t_s, people.xy_m[~waiting], people.v_m_s[~waiting])
        gaps = (
            self._gaps(stuck, others, now_s).min(1) if len(others) else np.full(len(cmds), np.inf)
        )
        if waiting.any():
            lanes = People(people.t_s, people.xy_m[waiting], people.intent_m_s[waiting])
            gaps = np.minimum(gaps, self._lane_gaps(stuck, lanes))
        if not backing and gaps[0] >= self.stop_m:
            return None  # the command keeps clear of everyone
        score = np.minimum(gaps, self.stop_m + self.margin_m)
        best = score.max()
        if best <= score[0] + 1e-6:
            return None
        pick = np.flatnonzero(score >= best - 1e-6)
        miss = np.hypot(cmds[pick, 0] - wanted[0], 0.3 * (cmds[pick, 1] - wanted[1]))
        choice = cmds[pick[np.argmin(miss)]]
        self.yields += 1
        return float(choice[0]), float(choice[1])
