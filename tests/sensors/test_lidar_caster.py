"""The LiDAR's beam caster: it sees the other robots at their range and never its own robot, and
a payload on its deck."""

import math

import mujoco
import numpy as np
import pytest

from amr_twin.model.build import build
from amr_twin.model.config import load_config
from amr_twin.sensors.lidar_beams import beam_angles_rad, beam_directions, scan_timing
from amr_twin.sensors.lidar_caster import BeamCaster
from amr_twin.sensors.lidar_kernels import beam_kernels


def _caster(model, data, cfg, site: str) -> tuple[BeamCaster, np.ndarray, np.ndarray]:
    """A caster on ``site`` and its outputs cast from the pose now: hit geoms, distances (m)."""
    n = scan_timing(cfg.lidar)[0]
    dirs = beam_directions(beam_angles_rad(n)[2])
    caster = BeamCaster(model, data, model.site(site).id, dirs, beam_kernels(n, cfg.lidar))
    geomid, dist = np.full(n, -1, np.int32), np.full(n, -1.0)
    caster.cast(0, n, np.zeros(n, np.int64), None, False, geomid, dist)
    return caster, geomid, dist


def test_a_robots_lidar_sees_the_other_robot_at_its_range_and_never_itself():
    from amr_twin.model.robot_starts import fleet_starts
    from amr_twin.sim.settled_physics import settled_fleet

    cfg = load_config()
    starts = fleet_starts([(-4.0, 0.0, 0.0), (-2.0, 0.0, 0.0)])  # robot 2 two metres ahead
    fleet = settled_fleet(cfg, "warehouse", starts, True, False, 0.3)
    one, two = fleet.robots
    m, d = one.model, one.data
    groups = m.geom_group.copy()
    caster, hit_geom, dist_m = _caster(m, d, cfg, "amr-1/laser")
    assert (m.geom_group == groups).all()  # its own geoms back in their group
    roots = m.body_rootid[m.geom_bodyid]
    hit = hit_geom[hit_geom >= 0]
    assert not (roots[hit] == m.body_rootid[one.base_body]).any()  # never its own body
    laser = d.site("amr-1/laser")
    ahead = laser.xmat.reshape(3, 3).T @ np.array([1.0, 0.0, 0.0])  # world +x in the laser frame
    beam = int(np.argmax(caster.local_dirs @ ahead))
    assert roots[hit_geom[beam]] == m.body_rootid[two.base_body]
    # the range: an independent ray from just beyond robot 1's nose along the same direction
    direction = laser.xmat.reshape(3, 3) @ caster.local_dirs[beam]
    start = laser.xpos + 0.2 * direction
    seen = np.array([1, 1, 0, 0, 0, 0], np.uint8)
    geom = np.zeros(1, np.int32)
    expected = 0.2 + mujoco.mj_ray(m, d, start, direction, seen, 1, -1, geom)
    assert geom[0] == hit_geom[beam] and dist_m[beam] == pytest.approx(expected, abs=1e-9)
    assert 1.2 < dist_m[beam] < 1.7  # to robot 2's back, 2 m less two half lengths


def test_a_payload_on_the_deck_is_seen_straight_back_at_its_front_face():
    cfg = load_config(overrides={"payload.mass_kg": 20.0, "payload.xy_m": [-0.15, 0.0]})
    m = build(cfg, world="warehouse").model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    _, hit_geom, dist_m = _caster(m, d, cfg, "amr/laser")
    back = 0  # angle -pi: straight back over the deck
    assert m.geom(int(hit_geom[back])).name == "amr/payload_box"
    laser, box = d.site("amr/laser"), d.geom("amr/payload_box")
    behind = laser.xmat.reshape(3, 3) @ np.array([math.cos(-math.pi), 0.0, 0.0])
    front_m = float((laser.xpos - box.xpos) @ -behind) - m.geom("amr/payload_box").size[0]
    assert dist_m[back] == pytest.approx(front_m, abs=1e-6)
