"""The episodes' pieces: an :class:`Episode`, the scenarios and where an unmapped obstacle or a
person goes.

Shared by the drawing of the hand-made worlds' episodes
(:func:`amr_twin.experiments.navigation.episodes`) and the generated halls' (:mod:`.generated`);
docs/explanation/navigation.md describes the scenarios."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from amr_twin.model.worlds import Obstacle

SCENARIOS = ("clear", "person", "pallet_jack")
SHARES = (0.5, 0.25, 0.25)
"""The share of episodes of each scenario."""
MIN_APART_M, MAX_APART_M = 10.0, 50.0
FREE_CLEARANCE_M = 0.7
PERSON_SIZE_M = (0.45, 0.30, 1.70)
JACK_SIZE_M = (1.60, 0.75, 1.30)


@dataclass(frozen=True)
class Episode:
    """One start/goal pair: poses ``(x_m, y_m, yaw_rad)``, its scenario, its unmapped obstacle (or
    None)."""

    index: int
    seed: int
    start: tuple
    goal: tuple
    scenario: str
    obstacle: Obstacle | None
    actor: object = None  # amr_twin.model.actors.Actor of a walking person
    doors: tuple = ()  # the doorways of a generated hall its reference plan crosses (a door trip)


def free_cells(costmap) -> np.ndarray:
    rows, cols = np.nonzero(costmap.static_dist_m >= FREE_CLEARANCE_M)
    return costmap.centres_xy_m(rows, cols)


ROBOT_SPEED_M_S = 0.55
"""The robot's mean speed on its way (from the episodes' times), to time a walking person's
crossing."""
CROSS_HALF_M = 0.7
STOP_WITHIN_M = 0.6
"""A walking person halts while the robot is this close ahead of them (people give way), m."""


def place(
    rng,
    scenario: str,
    plan,
    costmap,
    start,
    goal,
    people: str = "walking",
    clear_m: tuple[float, float] = (0.9, 1.1),
):
    """An obstacle (or a walking person: an Actor; ``people`` ``crossing``: one who does not give
    way) in an aisle on the planned way, at least 3 m from start and goal, its point ``clear_m``
    from the map's obstacles (the middle of a 2 m aisle); None if no room."""
    xy = plan.xy_m
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    d = costmap.static_distance_at(xy)
    ok = (s > 3.0) & (s < s[-1] - 3.0) & (d >= clear_m[0]) & (d <= clear_m[1])
    ok &= (np.hypot(*(xy - np.asarray(start[:2])).T) > 3.0) & (
        np.hypot(*(xy - np.asarray(goal[:2])).T) > 3.0
    )
    if not ok.any():
        return None
    i = int(rng.choice(np.flatnonzero(ok)))
    yaw = float(plan.poses[i, 2])
    if scenario == "person" and people in ("walking", "crossing"):
        from amr_twin.model.actors import Actor
        from amr_twin.navigation.stack import REST_S

        side = float(rng.choice([-1.0, 1.0]))
        n = np.array([-math.sin(yaw), math.cos(yaw)]) * side
        a, b = xy[i] - CROSS_HALF_M * n, xy[i] + CROSS_HALF_M * n
        start_s = max(0.0, REST_S + (s[i] - 3.0) / ROBOT_SPEED_M_S)
        return Actor(
            "person",
            ((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))),
            1.3,
            start_s=start_s,
            stop_within_m=STOP_WITHIN_M if people == "walking" else 0.0,
        )
    if scenario == "person":
        size, offset = PERSON_SIZE_M, float(rng.choice([-1.0, 1.0]) * rng.uniform(0.35, 0.6))
    else:
        size, offset = JACK_SIZE_M, float(rng.uniform(-0.55, 0.55))
    x = xy[i, 0] - math.sin(yaw) * offset
    y = xy[i, 1] + math.cos(yaw) * offset
    return Obstacle(scenario, float(x), float(y), size, yaw)
