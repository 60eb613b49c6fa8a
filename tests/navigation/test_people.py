"""The people tracker: leg clusters from scan to scan, their velocity, their predicted places
(synthetic scans)."""

import math

import numpy as np
import pytest

from amr_twin.navigation.people import PeopleTracker, clusters

SCAN_S = 0.18  # one RPLIDAR rotation


def _legs(x, y, heading_rad=0.0, spacing=0.2, r=0.06, n=6):
    """The returns of two legs (circles of ``r``) ``spacing`` apart across ``heading_rad``, seen
    from -y."""
    out = []
    for side in (-0.5, 0.5):
        cx, cy = (
            x - side * spacing * math.sin(heading_rad),
            y + side * spacing * math.cos(heading_rad),
        )
        a = np.linspace(-math.pi * 0.9, -math.pi * 0.1, n)  # the half facing the laser below them
        out.append(np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)]))
    return np.vstack(out)


def _feed(tracker, frames):
    for k, pts in enumerate(frames):
        tracker.update(pts, np.full(len(pts), k * SCAN_S), (0.0, -1.0), k * SCAN_S)
    return tracker.people()


def test_two_legs_are_one_cluster_and_a_wall_fragment_two_metres_long_is_not_a_person():
    legs = _legs(1.0, 0.0)
    assert len(set(clusters(legs, 0.3))) == 1
    assert len(set(clusters(np.vstack([legs, legs + [1.0, 0.0]]), 0.3))) == 2
    jack = np.column_stack([np.linspace(-0.8, 0.8, 40), np.full(40, 1.0)])
    centres, _t = PeopleTracker().detect(np.vstack([legs, jack]), np.zeros(len(legs) + 40))
    assert len(centres) == 1 and np.hypot(*(centres[0] - [1.0, 0.0])) < 0.08


def test_a_person_walking_across_is_tracked_at_their_velocity_and_predicted_ahead():
    v = np.array([0.0, 1.3])  # across, as the experiment's people walk
    frames = [
        _legs(2.0 + v[0] * k * SCAN_S, -1.0 + v[1] * k * SCAN_S, math.pi / 2) for k in range(12)
    ]
    people = _feed(PeopleTracker(), frames)
    assert len(people) == 1
    assert np.hypot(*(people.v_m_s[0] - v)) < 0.15, people.v_m_s
    ahead = people.at(np.array([people.t_s + 1.0]), horizon_s=2.5)[0, 0]
    truth = np.array([2.0, -1.0]) + v * (11 * SCAN_S + 1.0)
    assert np.hypot(*(ahead - truth)) < 0.2, (ahead, truth)
    capped = people.at(np.array([people.t_s + 5.0]), horizon_s=2.5)[0, 0]
    assert capped == pytest.approx(people.xy_m[0] + 2.5 * people.v_m_s[0])


def test_a_person_who_walked_and_stopped_stands_and_a_cluster_that_never_moved_is_no_person():
    rng = np.random.default_rng(0)
    walk = [_legs(1.0 + 1.2 * k * SCAN_S, 0.5) for k in range(5)]  # 0.86 m
    stand = [_legs(1.0 + 1.2 * 4 * SCAN_S, 0.5) + rng.normal(0.0, 0.01, (12, 2)) for _ in range(12)]
    people = _feed(PeopleTracker(), walk + stand)
    assert len(people) == 1 and not people.v_m_s.any()  # still a person, standing
    assert len(_feed(PeopleTracker(), stand)) == 0  # an upright the map lacks, say: the costmap's
    assert len(_feed(PeopleTracker(), walk[:1])) == 0  # seen once


def test_two_people_walking_past_each_other_keep_their_tracks():
    frames = [
        np.vstack(
            [_legs(-2.0 + 1.2 * k * SCAN_S, 0.0, 0.0), _legs(2.0 - 1.2 * k * SCAN_S, 1.0, math.pi)]
        )
        for k in range(10)
    ]
    people = _feed(PeopleTracker(), frames)
    assert len(people) == 2
    order = np.argsort(people.xy_m[:, 1])
    assert people.v_m_s[order[0], 0] == pytest.approx(1.2, abs=0.15)
    assert people.v_m_s[order[1], 0] == pytest.approx(-1.2, abs=0.15)


def test_a_person_out_of_sight_is_forgotten_and_returns_beyond_range_are_ignored():
    tracker = PeopleTracker(keep_s=0.6)
    _feed(tracker, [_legs(1.0 + 1.2 * k * SCAN_S, 0.0) for k in range(4)])  # walking
    tracker.update(np.zeros((0, 2)), np.zeros(0), (0.0, -1.0), 4 * SCAN_S)  # an empty scan
    assert len(tracker.people()) == 1  # not yet: unseen for one scan
    for k in range(5, 9):
        tracker.update(
            np.array([[50.0, 50.0]]), np.array([k * SCAN_S]), (0.0, -1.0), k * SCAN_S
        )  # out of range
    assert len(tracker.people()) == 0
