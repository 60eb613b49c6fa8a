"""The 3D entities of a ``.rrd`` recording, under ``world``, one ``_log_<stream>`` function per
stream.

Positions in m in the simulation's world frame (Z up), on the ``sim_time`` timeline::

    world/bodies/<body>                 Transform3D over time (robot bodies)
    world/bodies/<body>/geoms/<kind>    static Boxes3D / Ellipsoids3D / Cylinders3D
    world/bodies/amr/laser/scan         LaserScan points in the laser frame
    world/scan                          the same points in the world (deskewed per beam)
    world/trajectory/{true,odom}        LineStrips3D, growing at 2 Hz

The plots' streams are in :mod:`amr_twin.recording.rerun_streams`, the UWB's in
:mod:`amr_twin.recording.rerun_uwb`.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from amr_twin.recording.rerun_capture import Capture
from amr_twin.recording.rerun_streams import TIMELINE, _time
from amr_twin.sensors.lidar_beams import scan_end_time_s

VISUAL_GROUPS = (0, 1, 4)  # world, robot visuals, payload (2 is robot collision)


def body_entity(m: mujoco.MjModel, b: int) -> str:
    """The entity path of body ``b``: ``world/bodies/<body name>`` (``world/bodies/world`` for body
    0)."""
    name = m.body(b).name or f"body{b}"
    return "world/bodies/" + ("world" if b == 0 else name)


def _rgba(m: mujoco.MjModel, g: int) -> np.ndarray:
    mat = m.geom_matid[g]
    rgba = m.mat_rgba[mat] if mat >= 0 else m.geom_rgba[g]
    return (np.clip(rgba, 0, 1) * 255).astype(np.uint8)


def _log_geoms(rec, m: mujoco.MjModel) -> None:
    """Each body's visual geoms, once, static, in the body frame."""
    import rerun as rr

    T = mujoco.mjtGeom
    for b in range(m.nbody):
        kinds: dict[str, list] = {"boxes": [], "ellipsoids": [], "cylinders": []}
        for g in range(m.body_geomadr[b], m.body_geomadr[b] + m.body_geomnum[b]):
            if m.geom_group[g] not in VISUAL_GROUPS or m.geom_rgba[g][3] == 0:
                continue
            typ, size = int(m.geom_type[g]), m.geom_size[g]
            pos, q = m.geom_pos[g], m.geom_quat[g]
            xyzw = [q[1], q[2], q[3], q[0]]
            if typ == T.mjGEOM_BOX:
                kinds["boxes"].append((pos, xyzw, 2 * size, _rgba(m, g)))
            elif typ == T.mjGEOM_PLANE:
                half = [s if s > 0 else 15.0 for s in size[:2]]
                kinds["boxes"].append(
                    (pos - [0, 0, 0.001], xyzw, [2 * half[0], 2 * half[1], 0.002], _rgba(m, g))
                )
            elif typ == T.mjGEOM_SPHERE:
                kinds["ellipsoids"].append((pos, xyzw, [size[0]] * 3, _rgba(m, g)))
            elif typ == T.mjGEOM_ELLIPSOID:
                kinds["ellipsoids"].append((pos, xyzw, size[:3], _rgba(m, g)))
            elif typ in (int(T.mjGEOM_CYLINDER), int(T.mjGEOM_CAPSULE)):
                kinds["cylinders"].append((pos, xyzw, (size[0], 2 * size[1]), _rgba(m, g)))
        base = body_entity(m, b) + "/geoms/"
        for kind, items in kinds.items():
            if not items:
                continue
            centers = np.array([i[0] for i in items])
            quats = np.array([i[1] for i in items])
            colors = np.array([i[3] for i in items])
            if kind == "boxes":
                arch = rr.Boxes3D(
                    centers=centers,
                    quaternions=quats,
                    sizes=np.array([i[2] for i in items]),
                    colors=colors,
                    fill_mode="solid",
                )
            elif kind == "ellipsoids":
                arch = rr.Ellipsoids3D(
                    centers=centers,
                    quaternions=quats,
                    half_sizes=np.array([i[2] for i in items]),
                    colors=colors,
                    fill_mode="solid",
                )
            else:
                rl = np.array([i[2] for i in items])
                arch = rr.Cylinders3D(
                    centers=centers,
                    quaternions=quats,
                    radii=rl[:, 0],
                    lengths=rl[:, 1],
                    colors=colors,
                    fill_mode="solid",
                )
            rec.log(base + kind, arch, static=True)


def _log_body_transforms(rec, m, capture: Capture) -> None:
    import rerun as rr

    t, pos, quat = capture.body_poses()
    for j, b in enumerate(capture.body_ids):
        q = quat[:, j]
        rec.send_columns(
            body_entity(m, b),
            indexes=_time(t),
            columns=rr.Transform3D.columns(translation=pos[:, j], quaternion=q[:, [1, 2, 3, 0]]),
        )


TRAJECTORY_BLOCK_S = 10.0
"""The growing paths are logged in blocks of this many seconds, one entity each (linear size)."""


def _log_trajectory(rec, series, rate_hz: float = 2.0, root: str = "") -> None:
    """True (world) and odometry (odom frame put on the start pose) paths, growing.

    ``world/<root>trajectory/{true,odom}/<block>`` (``root``: ``amr-2/`` for a robot of a
    fleet): each block of :data:`TRAJECTORY_BLOCK_S` is a line strip that grows at ``rate_hz``
    from the end of the block before it and then stays (the viewer keeps an entity's latest
    strip), so a run of any length costs a file that grows linearly with it, not with its square.
    """
    import rerun as rr

    true_xy = series.pose[:, :2]
    x0, y0, yaw0 = series.pose[0]
    c, s = math.cos(yaw0), math.sin(yaw0)
    odom = series.odom
    odom_xy = np.column_stack(
        [x0 + c * odom[:, 1] - s * odom[:, 2], y0 + s * odom[:, 1] + c * odom[:, 2]]
    )
    end = float(series.t_s[-1]) if len(series.t_s) else 0.0
    for t in np.append(np.arange(0.0, end, 1.0 / rate_hz), end):
        rec.set_time(TIMELINE, duration=float(t))
        block = int(t // TRAJECTORY_BLOCK_S)
        t_block = block * TRAJECTORY_BLOCK_S
        for name, tt, xy, color in (
            ("true", series.t_s, true_xy, (40, 160, 40)),
            ("odom", odom[:, 0], odom_xy, (220, 60, 60)),
        ):
            n = int(np.searchsorted(tt, t, side="right"))
            first = max(
                0, int(np.searchsorted(tt, t_block, side="left")) - 1
            )  # joins the block before
            if n - first >= 2:
                pts = np.vstack([xy[first:n:5], xy[n - 1 : n]])
                pts = np.column_stack([pts, np.full(len(pts), 0.01)])
                rec.log(
                    f"world/{root}trajectory/{name}/{block:04d}",
                    rr.LineStrips3D([pts], colors=[color], radii=[0.01]),
                )


def _pose_track(capture: Capture, m, body: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sample times (n,), s, positions (n, 3), m, and unwrapped yaw (n,), rad, of ``body``."""
    j = int(
        np.nonzero(capture.body_ids == mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body))[0][0]
    )
    t, pos, quat = capture.body_poses()
    q = quat[:, j]
    yaw = np.unwrap(
        np.arctan2(
            2 * (q[:, 0] * q[:, 3] + q[:, 1] * q[:, 2]), 1 - 2 * (q[:, 2] ** 2 + q[:, 3] ** 2)
        )
    )
    return t, pos[:, j], yaw


def _interp_pose(track, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position (n, 3) and yaw (n,) of a :func:`_pose_track` at ``t_s``, linear between samples."""
    t, pos, yaw = track
    return np.column_stack([np.interp(t_s, t, pos[:, k]) for k in range(3)]), np.interp(t_s, t, yaw)


def _body_pose_at(capture: Capture, m, body: str, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position (n, 3), m, and yaw (n,), rad, of ``body`` at ``t_s``, interpolated from the body
    samples."""
    return _interp_pose(_pose_track(capture, m, body), t_s)


def _log_scan(rec, m, capture: Capture, laser: str = "amr/laser", root: str = "") -> None:
    """Every scan in the laser frame and in the world (each beam at its own instant's laser pose):
    ``world/bodies/<laser>/scan`` and ``world/<root>scan`` (``laser``: the laser's body).

    The laser's pose track is made once and all beams of all scans are placed in one
    vectorised pass: the cost grows with the number of beams, not with their square.
    """
    import rerun as rr

    scans = capture.messages.get("scan", [])
    if not scans:
        return
    ranges, t_beam, angles, ends = [], [], [], []
    for _t_us, msg in scans:
        r = np.asarray(msg.ranges, float)
        i = np.arange(len(r))
        ranges.append(r)
        angles.append(msg.angle_min + msg.angle_increment * i)
        t_beam.append(msg.header.stamp.to_sec() + msg.time_increment * i)
        ends.append(scan_end_time_s(msg))
    sizes = [len(r) for r in ranges]
    r, ang, t_all = np.concatenate(ranges), np.concatenate(angles), np.concatenate(t_beam)
    ok = np.isfinite(r)
    r = np.where(ok, r, 0.0)  # no return: inf; dropped below, kept out of the products
    local = np.column_stack([r * np.cos(ang), r * np.sin(ang), np.zeros_like(r)])
    p, yaw = _interp_pose(_pose_track(capture, m, laser), t_all)
    c, s = np.cos(yaw), np.sin(yaw)
    world = np.column_stack(
        [
            p[:, 0] + c * local[:, 0] - s * local[:, 1],
            p[:, 1] + s * local[:, 0] + c * local[:, 1],
            p[:, 2],
        ]
    )
    # one row per scan at the end of its rotation, its beams with a return: two columnar sends
    bounds = np.r_[0, np.cumsum(sizes)]
    kept = np.diff(np.r_[0, np.cumsum(ok)][bounds])  # beams with a return, per scan
    for entity, points, colour, radius in (
        (f"world/bodies/{laser}/scan", local, (250, 200, 40), 0.01),
        (f"world/{root}scan", world, (40, 120, 250), 0.015),
    ):
        style = rr.Points3D.columns(
            colors=np.tile(colour, (len(sizes), 1)), radii=np.full(len(sizes), radius)
        )
        rec.send_columns(
            entity,
            indexes=_time(ends),
            columns=[*rr.Points3D.columns(positions=points[ok]).partition(kept), *style],
        )
