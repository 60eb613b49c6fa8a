"""The navigation stack in a ``.rrd`` recording: the map, the plan, the local costmap, the
footprint.

From the bus messages the capture kept (:mod:`amr_twin.navigation.outputs` publishes them), on the
``sim_time`` timeline, in the world frame (the navigation's ``map``)::

    world/navigation/map        static Points3D: the static map's occupied cells (z = 0.01 m)
    world/navigation/plan       LineStrips3D: each new plan (z = 0.03 m)
    world/navigation/costmap    Points3D: the local costmap's cells with a cost, coloured by it
                                (z = 0.02 m)
    world/navigation/footprint  LineStrips3D: the footprint at the estimated pose (z = 0.05 m)
"""

from __future__ import annotations

import numpy as np

from amr_twin.recording.rerun_streams import TIMELINE


def _cells(msg, keep) -> tuple[np.ndarray, np.ndarray]:
    """Centres (K, 2) of the cells of an OccupancyGrid where ``keep(data)`` holds, and their
    values."""
    i = msg.info
    data = np.asarray(msg.data).reshape(i.height, i.width)
    rows, cols = np.nonzero(keep(data))
    xy = np.column_stack(
        [
            i.origin.position.x + (cols + 0.5) * i.resolution,
            i.origin.position.y + (rows + 0.5) * i.resolution,
        ]
    )
    return xy, data[rows, cols]


def _log_navigation(rec, capture, root: str = "") -> None:
    """The streams of the module notes (a robot of a fleet's under ``world/<root>navigation``:
    ``root`` ``amr-2/``)."""
    import rerun as rr

    msgs = capture.messages
    for _t, m in msgs.get("map", [])[:1]:
        xy, _ = _cells(m, lambda d: d == 100)
        rec.log(
            f"world/{root}navigation/map",
            rr.Points3D(
                np.column_stack([xy, np.full(len(xy), 0.01)]), radii=0.025, colors=(60, 60, 60)
            ),
            static=True,
        )
    for t_us, m in msgs.get("plan", []):
        rec.set_time(TIMELINE, duration=t_us * 1e-6)
        pts = np.array([[p.pose.position.x, p.pose.position.y, 0.03] for p in m.poses])
        rec.log(
            f"world/{root}navigation/plan",
            rr.LineStrips3D([pts], colors=(30, 120, 255), radii=0.015),
        )
    for t_us, m in msgs.get("local_costmap/costmap", []):
        rec.set_time(TIMELINE, duration=t_us * 1e-6)
        xy, v = _cells(m, lambda d: d > 0)
        colour = np.column_stack(
            [np.full(len(v), 255), 255 - 2.5 * np.clip(v, 0, 100), np.full(len(v), 40)]
        )
        rec.log(
            f"world/{root}navigation/costmap",
            rr.Points3D(
                np.column_stack([xy, np.full(len(xy), 0.02)]),
                radii=0.025,
                colors=colour.astype(np.uint8),
            ),
        )
    for t_us, m in msgs.get("local_costmap/published_footprint", []):
        rec.set_time(TIMELINE, duration=t_us * 1e-6)
        pts = np.array(
            [[p.x, p.y, 0.05] for p in m.points] + [[m.points[0].x, m.points[0].y, 0.05]]
        )
        rec.log(
            f"world/{root}navigation/footprint",
            rr.LineStrips3D([pts], colors=(0, 200, 200), radii=0.01),
        )
