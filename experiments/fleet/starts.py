"""Where the fleet experiment's robots start: on rack-face nodes of the manager's roadmap, the
nearest to the world's start first (by the charging dock), so that a robot waiting there holds its
node (a robot off the roadmap does not: a route may lead through it).

Robot ``i`` of a fleet starts at the same node whatever the fleet's size; each faces along an edge
of its node (towards its first neighbour by node id).
"""

from __future__ import annotations

import math


def start_poses(
    roadmap, around_xy: tuple[float, float], robots: int, half_length_m: float, half_width_m: float
) -> tuple[tuple[float, float, float], ...]:
    """``robots`` start poses (x_m, y_m, yaw_rad) on distinct ``aisle`` nodes of ``roadmap`` (a
    :class:`~amr_twin.fleet_manager.roadmap.Roadmap`), nearest ``around_xy`` (m) first, ties by
    node id; a node whose robot (``half_length_m`` by ``half_width_m`` about its centre, m) would
    overlap an earlier one is skipped. ValueError (one line) if the roadmap has too few."""
    from amr_twin.model.robot_starts import overlapping_starts

    faces = sorted(
        roadmap.nodes_of("aisle"), key=lambda n: (math.dist(roadmap.xy(n), around_xy), n)
    )
    poses: list[tuple[float, float, float]] = []
    for node in faces:
        if len(poses) == robots:
            break
        x, y = roadmap.xy(node)
        nx_, ny_ = roadmap.xy(min(roadmap.graph.neighbors(node)))
        pose = (round(float(x), 3), round(float(y), 3), round(math.atan2(ny_ - y, nx_ - x), 4))
        if overlapping_starts([*poses, pose], half_length_m, half_width_m) is None:
            poses.append(pose)
    if len(poses) < robots:
        raise ValueError(
            f"--robots {robots}: map {roadmap.map_id!r} has {len(poses)} rack-face nodes "
            "far enough apart to start robots on"
        )
    return tuple(poses)
