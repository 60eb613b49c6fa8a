"""Planar pose algebra (amr_twin.analysis.se2), no mujoco."""

import math

import numpy as np
import pytest

from amr_twin.analysis import se2


def test_compose_then_between_is_identity():
    rng = np.random.default_rng(1)
    a = rng.uniform([-5, -5, -math.pi], [5, 5, math.pi], size=(50, 3))
    b = rng.uniform([-5, -5, -math.pi], [5, 5, math.pi], size=(50, 3))
    np.testing.assert_allclose(se2.between(a, se2.compose(a, b)), b, atol=1e-12)


def test_compose_known_case():
    # a point 1 m ahead of a robot at (2, 3) facing +y is at (2, 4)
    np.testing.assert_allclose(
        se2.compose([2.0, 3.0, math.pi / 2], [1.0, 0.0, 0.0]), [2.0, 4.0, math.pi / 2], atol=1e-12
    )


def test_wrap_and_interpolation_across_pi():
    assert se2.wrap_rad(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    t = np.array([0.0, 1.0])
    pose = np.array([[0.0, 0.0, math.pi - 0.1], [1.0, 0.0, -math.pi + 0.1]])
    mid = se2.interpolate(t, pose, 0.5)
    assert abs(abs(mid[2]) - math.pi) < 1e-9  # through pi, not through 0
    assert mid[0] == pytest.approx(0.5)


def test_compose_and_relative_pose_are_inverse():
    a = np.array([1.0, -2.0, 3.0])  # near +pi: the yaw sum must wrap
    b = np.array([[0.5, 0.25, 0.5], [-1.0, 2.0, -2.0]])
    ab = se2.compose(a, b)
    assert np.all(np.abs(ab[:, 2]) <= math.pi)
    np.testing.assert_allclose(se2.between(a, ab), b, atol=1e-12)
    # 0.30 m ahead of a base turned 90 deg left is 0.30 m along +y
    np.testing.assert_allclose(
        se2.compose([0.0, 0.0, math.pi / 2], (0.30, 0.0, 0.0)), [0.0, 0.30, math.pi / 2], atol=1e-12
    )


def test_interpolate_pose_across_the_yaw_wrap():
    t = np.array([0.0, 1.0])
    pose = np.array([[0.0, 0.0, math.pi - 0.1], [1.0, 2.0, -math.pi + 0.1]])  # +0.2 rad through pi
    mid = se2.interpolate(t, pose, 0.5)
    np.testing.assert_allclose(mid[:2], [0.5, 1.0])
    assert abs(abs(mid[2]) - math.pi) < 1e-9
    np.testing.assert_allclose(se2.interpolate(t, pose, [-1.0, 2.0]), pose)  # held beyond the ends


def test_matrix_round_trip():
    pose = (1.5, -0.25, 2.9)
    assert se2.from_matrix(se2.matrix(*pose)) == pytest.approx(pose)
    np.testing.assert_allclose(
        se2.matrix(*pose) @ se2.matrix(*pose)[:, [3]],
        se2.matrix(*se2.compose(pose, pose))[:, [3]],
        atol=1e-12,
    )


def test_inverse_undoes_a_pose_on_either_side():
    rng = np.random.default_rng(4)
    a = np.column_stack([rng.uniform(-5, 5, (20, 2)), rng.uniform(-math.pi, math.pi, 20)])
    for left, right in ((a, se2.inverse(a)), (se2.inverse(a), a)):
        np.testing.assert_allclose(se2.compose(left, right), np.zeros_like(a), atol=1e-12)
    np.testing.assert_allclose(
        se2.inverse([1.0, 0.0, math.pi / 2]), [0.0, 1.0, -math.pi / 2], atol=1e-12
    )


def _mul(a, b):
    """Hamilton product of quaternions (w, x, y, z)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def test_the_yaw_of_a_quaternion_is_its_zyx_heading_even_when_tilted():
    """q = yaw about z, then pitch about y, then roll about x (ZYX): its yaw is the first angle."""
    rng = np.random.default_rng(5)
    qs, yaws = [], []
    for yaw, pitch, roll in zip(
        rng.uniform(-3.1, 3.1, 50), rng.uniform(-1.2, 1.2, 50), rng.uniform(-1.2, 1.2, 50)
    ):
        qz = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
        qy = (math.cos(pitch / 2), 0.0, math.sin(pitch / 2), 0.0)
        qx = (math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0)
        q = _mul(_mul(qz, qy), qx)
        assert se2.yaw_of_quaternion(*q) == pytest.approx(yaw, abs=1e-12)
        qs.append(q)
        yaws.append(yaw)
    assert se2.yaws_of_quaternions(np.array(qs)) == pytest.approx(np.array(yaws), abs=1e-12)
    assert se2.yaw_of_quaternion(0.0, 0.0, 0.0, 1.0) == pytest.approx(math.pi)  # half a turn
