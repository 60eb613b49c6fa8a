"""Fleet mates: a robot that knows the others' poses does not take them for people (it does not
give way to a robot ahead as to a person), yet keeps them as obstacles; a member without a pose
and the robot itself claim no returns."""

import numpy as np

from amr_twin.assembly.fleet_world import fleet_world
from amr_twin.assembly.twin import TwinOptions
from amr_twin.model.config import load_config
from amr_twin.navigation.fleet_mates import FleetMates
from amr_twin.navigation.stack import REST_S, NavigationOptions, attach, fleet_mates
from amr_twin.navigation.stack import load_static_map

CFG = load_config()


class _Source:
    def __init__(self, pose):
        self.ready, self._pose = pose is not None, pose

    def pose(self):
        return self._pose


def test_returns_near_another_member_are_its_own_not_near_the_robot_itself():
    fleet = FleetMates(0.5)
    me = fleet.join(_Source((0.0, 0.0, 0.0)))
    fleet.join(_Source((2.0, 0.0, 0.0)))
    fleet.join(_Source(None))  # no pose yet: claims nothing
    points = np.array([[0.1, 0.0], [1.6, 0.0], [2.4, 0.3], [3.0, 0.0]])
    assert fleet.theirs(me, points).tolist() == [False, True, True, False]
    assert fleet.theirs(1, points).tolist() == [True, False, False, False]


def _follow(shared: bool):
    """A robot 1.5 m behind another in one lane of the warehouse's aisle, both driving 5 m
    ahead: the follower's people and yields, and the least gap between their centres."""
    starts = [(-4.5, -1.0, 0.0), (-6.0, -1.0, 0.0)]
    options = TwinOptions(world="warehouse", firmware="improved", sensors=("imu", "lidar"))
    world = fleet_world(CFG, options, starts)
    static = load_static_map(CFG, "warehouse", None)
    fleet = fleet_mates(CFG) if shared else None
    navs = [
        attach(
            robot,
            CFG,
            static,
            NavigationOptions(goals=((x + 5.0, y, yaw),), seed=i),
            publish=False,
            fleet=fleet,
        )
        for i, (robot, (x, y, yaw)) in enumerate(zip(world.robots, starts))
    ]
    world.advance(REST_S + 0.5)
    seen, gap = 0, np.inf
    for _ in range(30):
        world.advance(0.1)
        seen = max(seen, len(navs[1].people))
        a, b = (r.physics.pose() for r in world.robots)
        gap = min(gap, float(np.hypot(a.x_m - b.x_m, a.y_m - b.y_m)))
    return seen, navs[1].yielding.yields, gap, world.collision_records()


def test_a_robot_ahead_is_a_mate_to_follow_not_a_person_to_give_way_to():
    seen, yields, gap, hits = _follow(shared=True)
    assert seen == 0 and yields == 0
    assert hits == [] and gap > 0.9  # still an obstacle: kept behind it
    seen, yields, _, _ = _follow(shared=False)
    assert seen > 0 and yields > 0  # without the shared poses: a person walking ahead
