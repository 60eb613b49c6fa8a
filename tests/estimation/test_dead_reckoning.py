"""The smoothed pose's shortcut between knots gives :func:`integrate`'s pose to the bit."""

from amr_twin.estimation.dead_reckoning import SmoothedPose, integrate


def _body(left_rpm: float, right_rpm: float) -> tuple[float, float]:
    v_left, v_right = left_rpm * 0.0130899694, right_rpm * 0.0131
    return 0.5 * (v_left + v_right), (v_right - v_left) / 0.48


def test_pose_between_knots_is_integrates_bit_for_bit():
    smoothed = SmoothedPose(0, (0.3, -0.2, 0.4), (50.0, 47.0), _body, 10_000)
    left, right = smoothed.profiles
    # constant to a knot ahead of now (an assumed ramp to rest), then varying: the shortcut ends
    # there
    left.point(400_000, 50.0)
    left.point(900_000, 10.0)
    right.window(0, 300_000, 47.0)
    right.point(700_000, 12.0)
    smoothed.changed()
    for now_us in range(20_000, 1_000_000, 17_003):
        expected = integrate(smoothed.profiles, smoothed._cache, now_us, 10_000, _body)[1:]
        assert smoothed.pose_at(now_us) == expected, now_us
