"""Regenerate docs/img/actors_lidar.png: what the RPLIDAR at 0.45 m sees of a person and a pallet
jack.

One scan of the twin (standing at the warehouse's start, IMU and LiDAR on) with a person crossing
2.2 m ahead at 1.2 m/s and a pallet jack standing forks-first 3 m ahead to the left: the scan's
points in the world (each beam from the laser pose at its own instant), the actors' outlines at
the scan's end (legs and pump: the geoms the 0.45 m plane cuts, solid; torso, forks and frame:
out of the plane, dashed), and the person's path with its pose every 0.1 s from actors/poses.

Usage: python docs/img/make_actors_figure.py [OUT.png]
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, Polygon  # noqa: E402

from amr_twin import Actor, Twin, TwinOptions, load_config  # noqa: E402


def _rect(x, y, yaw, x0, x1, y0, y1, **kw):
    c, s = math.cos(yaw), math.sin(yaw)
    pts = [
        (x + c * a - s * b, y + s * a + c * b) for a, b in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))
    ]
    return Polygon(pts, closed=True, fill=False, **kw)


def main(out: Path) -> None:
    cfg = load_config()
    p, j = cfg.actors.person, cfg.actors.pallet_jack
    person = Actor("person", ((-3.5, 1.6), (-3.5, -1.6)), 1.2, start_s=0.3)
    jack = Actor(
        "pallet_jack", ((-2.2, 1.6), (-3.2, 1.6)), 1.0, start_s=1e5
    )  # forks toward -x: toward the robot
    twin = Twin(
        cfg,
        TwinOptions(
            start_xy_yaw=(-6.0, 0.0, 0.0),
            sensors=("imu", "lidar"),
            actors=(person, jack),
            visuals=False,
        ),
    )
    scans, poses = [], []
    twin.bus.subscribe("scan", scans.append, queue_size=100)
    twin.bus.subscribe("actors/poses", poses.append, queue_size=100)
    twin.advance(1.75)
    scan = scans[-1]
    laser = twin.physics.site_position_m("amr/laser")[:2]
    r = np.asarray(scan.ranges, float)
    a = scan.angle_min + scan.angle_increment * np.arange(len(r))
    ok = np.isfinite(r)
    xy = laser + np.column_stack([r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])])
    t_end = scan.header.stamp.to_sec()
    (px, py, pyaw), (jx, jy, jyaw) = [
        (q.position.x, q.position.y, q.orientation.yaw_rad())
        for q in poses[int(round(t_end * 10))].poses
    ]

    fig, ax = plt.subplots(figsize=(8, 7.2))
    ax.plot(
        xy[:, 0],
        xy[:, 1],
        ".",
        ms=3,
        color="tab:blue",
        label=f"scan (one rotation, ending {t_end:.2f} s)",
    )
    track = np.array(
        [
            [q.poses[0].position.x, q.poses[0].position.y]
            for q in poses
            if q.header.stamp.to_sec() <= t_end + 1e-9
        ]
    )
    ax.plot(
        track[:, 0],
        track[:, 1],
        "o",
        ms=2.5,
        color="tab:orange",
        label="person on actors/poses, every 0.1 s",
    )
    half = p.leg_spacing_m / 2
    for s in (1, -1):  # legs: the plane cuts them
        ax.add_patch(
            Circle(
                (px - s * math.sin(pyaw) * half, py + s * math.cos(pyaw) * half),
                p.leg_radius_m,
                fill=False,
                color="k",
                lw=1.2,
            )
        )
    ax.add_patch(
        _rect(
            px,
            py,
            pyaw,
            -p.torso_depth_m / 2,
            p.torso_depth_m / 2,
            -p.torso_width_m / 2,
            p.torso_width_m / 2,
            ls="--",
            color="grey",
            lw=0.8,
        )
    )
    front, heel, back = j.length_m / 2, j.length_m / 2 - j.fork_length_m, -j.length_m / 2
    for y0 in (j.width_m / 2 - j.fork_width_m, -j.width_m / 2):  # forks, frame: below the plane
        ax.add_patch(
            _rect(jx, jy, jyaw, heel, front, y0, y0 + j.fork_width_m, ls="--", color="grey", lw=0.8)
        )
    ax.add_patch(
        _rect(
            jx, jy, jyaw, back, heel, -j.width_m / 2, j.width_m / 2, ls="--", color="grey", lw=0.8
        )
    )
    cx = back + j.pump_radius_m
    ax.add_patch(
        Circle(
            (jx + math.cos(jyaw) * cx, jy + math.sin(jyaw) * cx),
            j.pump_radius_m,
            fill=False,
            color="k",
            lw=1.2,
        )
    )
    ax.add_patch(
        _rect(
            -6.0,
            0.0,
            0.0,
            -cfg.chassis.length_m / 2,
            cfg.chassis.length_m / 2,
            -cfg.chassis.width_m / 2,
            cfg.chassis.width_m / 2,
            color="tab:green",
            lw=1.2,
        )
    )
    ax.plot([], [], "k-", label="cut by the 0.45 m scan plane (legs, pump)")
    ax.plot([], [], "--", color="grey", label="out of the plane (torso; forks 0.085 m, frame)")
    ax.plot([], [], "-", color="tab:green", label="robot footprint")
    ax.set_xlim(-6.6, -0.8)
    ax.set_ylim(-3.3, 3.3)
    ax.set_aspect("equal")
    ax.set_xlabel("x, m (world)")
    ax.set_ylabel("y, m (world)")
    ax.set_title("What the LiDAR sees: a person crossing at 1.2 m/s, a pallet jack forks first")
    ax.legend(loc="lower right", fontsize=7.5, framealpha=0.95)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).with_name("actors_lidar.png"))
