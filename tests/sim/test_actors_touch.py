"""Actors never walk through the robot: a person walking into a standing robot stops against it, the
touch is a reported collision of a person's push (not a kinematic body's shove), and a person giving
way walks on after ``give_way_s``."""

import pytest

from amr_twin.model.actors import Actor
from amr_twin.model.config import load_config
from amr_twin.assembly.twin import Twin, TwinOptions

CFG = load_config()
START = (-6.0, 0.0, 0.0)  # the warehouse's main aisle


def _run(actor, seconds):
    twin = Twin(CFG, TwinOptions(start_xy_yaw=START, actors=(actor,), visuals=False))
    twin.advance(seconds)
    return twin


@pytest.mark.parametrize(
    "path",
    [
        ((-2.5, 0.0), (-8.0, 0.0)),  # head on into its front
        ((-5.8, 2.4), (-5.8, -2.4)),  # across its side, into a wheel
        ((-3.0, 2.0), (-7.5, -1.0)),
    ],
)  # at a slant into its front corner
def test_a_person_walking_into_a_standing_robot_stops_against_it_with_a_persons_push(path):
    """Measured: 6-14 N peak; a kinematic body walked on through the robot (the old rule) shoves it
    aside with kN and carries it along."""
    twin = _run(Actor("person", path, 1.3), 6.0)
    hits = twin.collisions.as_dicts()
    assert [h["hit"] for h in hits] == ["person_0"]  # the touch is a collision
    assert hits[0]["peak_force_n"] < 200.0  # a person's push
    pose = twin.physics.pose()
    assert (
        abs(pose.x_m - START[0]) < 0.01 and abs(pose.y_m) < 0.01 and abs(pose.yaw_rad) < 0.03
    )  # not shoved
    assert twin.actors.held_s()[0] > 2.0  # they stood against it


def test_a_person_giving_way_walks_on_after_give_way_s_and_stops_on_touching():
    give = CFG.actors.person.give_way_s
    twin = _run(Actor("person", ((-2.5, 0.0), (-8.0, 0.0)), 1.3, stop_within_m=1.0), 10.0)
    walked = twin.actors.progress_s()[0]
    # 1.87 m to the 1 m line at 1.3 m/s, then the wait, then 1 m on to the robot's front (0.06 m
    # legs)
    to_line = (-2.5 - (START[0] + CFG.chassis.length_m / 2) - 1.0) / 1.3
    assert to_line + 0.5 < walked < 10.0 - give + 0.05
    hits = twin.collisions.as_dicts()
    assert [h["hit"] for h in hits] == ["person_0"] and hits[0]["t_s"] > to_line + give
    assert hits[0]["peak_force_n"] < 200.0 and abs(twin.physics.pose().x_m - START[0]) < 0.01
